"""The `5tuple` view: one row per bidirectional 5-tuple flow (the default, and the paper's)."""

from __future__ import annotations

from .flow import flow_view
from .registry import register

VIEW = register(flow_view("5tuple", "one flow per 5-tuple connection"))
