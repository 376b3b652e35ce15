"""The `hostpair` view: one row per host pair over the run (ports and protocol ignored)."""

from __future__ import annotations

from .flow import flow_view
from .registry import register

VIEW = register(flow_view("hostpair", "one flow per host pair"))
