"""Feature standards, one module each, registered by name (see `base.FeatureStandard`).

Adding a standard: one module here that builds a `FeatureStandard` (columns, units, meanings,
source, compute, episode summary) and passes it to `register` (plus its tests). Every module of
this package is imported below, so nothing else needs editing: the CLI's `--features` choices,
the dataset card, the data dictionary, the Parquet schema and the IDS feature sets read the
registry.
"""

from __future__ import annotations

import importlib
import pkgutil

from .base import FeatureStandard, FlowPackets
from .registry import DEFAULT_STANDARD, episode_feature_columns, feature_columns, names, register, standard, standards

_INFRA = {"base", "meanings", "registry"}  # shared code, no standard
for _m in pkgutil.iter_modules(__path__):
    if _m.name not in _INFRA:
        importlib.import_module(f"{__name__}.{_m.name}")

standard(DEFAULT_STANDARD)  # the default must be registered (a one-line error otherwise)

__all__ = ["DEFAULT_STANDARD", "FeatureStandard", "FlowPackets", "episode_feature_columns", "feature_columns", "names",
           "register", "standard", "standards"]
