"""Dataset views, one module each, registered by name (see `base.ViewSpec`).

A view is what a run is extracted to: one row per flow (`5tuple`, `hostpair`, `window-hostpair`)
or one row per plan node per plan window (`window-host`, whose rows are called episodes,
`uavcas.labels.episodes`). Adding a view: one module here that builds a `ViewSpec` (name, row
noun, key and columns, Arrow fields per feature standard, data-dictionary entries, labeller and
extraction) and passes it to `register` (plus its tests). Every module of this package is
imported below, so nothing else needs editing: `uavcas extract --view`, the campaign's `--view`,
the dataset store and card, the Croissant metadata and README, the report, `uavcas info` and the
IDS feature sets read the registry (tests/views/test_view_dropin.py drops one in).
"""

from __future__ import annotations

import importlib
import pkgutil

from .base import RowNoun, ViewInput, ViewRows, ViewSpec
from .registry import DEFAULT_VIEW, card_view, frame_view, names, recorded_view, register, view, views

_INFRA = {"base", "registry", "flow"}  # shared code, no view
for _m in pkgutil.iter_modules(__path__):
    if _m.name not in _INFRA:
        importlib.import_module(f"{__name__}.{_m.name}")

view(DEFAULT_VIEW)  # the default must be registered (a one-line error otherwise)

__all__ = ["DEFAULT_VIEW", "RowNoun", "ViewInput", "ViewRows", "ViewSpec", "card_view", "frame_view",
           "names", "recorded_view", "register", "view", "views"]
