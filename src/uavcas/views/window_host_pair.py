"""The `window-hostpair` view: one row per host pair per plan window (the paper's host-pair flows)."""

from __future__ import annotations

from .flow import flow_view
from .registry import register

VIEW = register(flow_view("window-hostpair", "one flow per host pair per plan window"))
