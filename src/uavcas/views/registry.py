"""The one registry of dataset views: name -> `ViewSpec`.

`uavcas extract --view` and `uavcas campaign run --view` offer `names()`; the dataset store,
card, Croissant metadata, README, report, data dictionary, CSV exports and the IDS feature sets
look a dataset's view up here (`view`, or the view a dataset / shard / frame records), never
branch on its name.
"""

from __future__ import annotations

from collections.abc import Mapping

import pandas as pd

from .base import ViewSpec

_REGISTRY: dict[str, ViewSpec] = {}
DEFAULT_VIEW = "5tuple"  # a row is a flow of the 5-tuple key: the paper's, and files that record no view


def register(spec: ViewSpec) -> ViewSpec:
    """Make `spec` the view of its name; a module calls it once at import."""
    if spec.name in _REGISTRY:
        raise ValueError(f"view {spec.name!r} registered twice")
    _REGISTRY[spec.name] = spec
    return spec


def names() -> tuple[str, ...]:
    """Every registered view's name, in the package's module order."""
    return tuple(_REGISTRY)


def views() -> tuple[ViewSpec, ...]:
    return tuple(_REGISTRY.values())


def view(name: str) -> ViewSpec:
    """The view called `name`; an unknown name is a one-line ValueError listing the known."""
    try:
        return _REGISTRY[name]
    except (KeyError, TypeError):
        raise ValueError(f"unknown view {name!r}; known: {', '.join(_REGISTRY)}") from None


def recorded_view(meta: Mapping) -> ViewSpec:
    """The view a shard's metadata (or a card's run record) names; none named (an imported
    layout, a file before views were recorded): the default, whose rows are flows."""
    return view(meta.get("view") or DEFAULT_VIEW)


def card_view(card: Mapping) -> ViewSpec:
    """The view of a dataset's rows, from its card: its first recorded view (every view of one
    dataset has one unit, so they describe its rows alike), else the first view of the card's
    `unit`, else the default."""
    recorded = card.get("views") or []
    if recorded:
        return view(recorded[0])
    unit = card.get("unit")
    return next((v for v in views() if v.unit == unit), view(DEFAULT_VIEW))


def frame_view(df: pd.DataFrame) -> ViewSpec:
    """The view of a frame's rows: the one its `view` column names when every row names the same
    registered view, else the default (flows of an external dataset, a mix)."""
    if "view" not in df.columns or len(df) == 0:
        return view(DEFAULT_VIEW)
    seen = pd.unique(df["view"].astype(str))
    return _REGISTRY.get(str(seen[0]), view(DEFAULT_VIEW)) if len(seen) == 1 else view(DEFAULT_VIEW)
