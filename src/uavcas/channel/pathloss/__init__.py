"""Path-loss models, one module each, registered by scenario name (see `base.PathLossModel`).

Adding a model: one module here defining the model class (``samples_los``, ``loss_db(geom)``,
``evaluate(geom, los_uniform)``, and ``p_los(geom)`` plus ``los_corr_m`` if it has a LOS state)
and calling `register(PathLossSpec(...))` with its name, standard and version, and calibration
fit if any; plus its tests. Every module of this package is imported below, so the scenario codec,
the CLI and the data dictionary offer it without further edits (docs/architecture.md has a worked
example).
"""

from __future__ import annotations

import importlib
import pkgutil

from .base import DEFAULT_FC_GHZ, LosPathLossModel, PathLossModel, PathLossOptions, PathLossSpec
from .registry import PathlossName, check_name, help_text, make_pathloss, names, register, spec, specs

_INFRA = {"base", "registry"}  # shared code, no model
for _m in pkgutil.iter_modules(__path__):
    if _m.name not in _INFRA:
        importlib.import_module(f"{__name__}.{_m.name}")

# Re-exported: the models that other packages (calibration, twin profile) build directly.
from .freespace import FreeSpace, free_space_loss_db  # noqa: E402
from .logdist import (  # noqa: E402
    PAPER_ANCHORED_PROFILE,
    PAPER_RELATIVE_PROFILE,
    PROFILES,
    LogDistance,
    PathLossProfile,
    get_profile,
)
from .tr36777 import AerialModel, RMaAV, UMaAV, UMiAV  # noqa: E402
from .tworay import TwoRay  # noqa: E402

__all__ = [
    "DEFAULT_FC_GHZ", "PAPER_ANCHORED_PROFILE", "PAPER_RELATIVE_PROFILE", "PROFILES", "AerialModel", "FreeSpace",
    "LogDistance", "LosPathLossModel", "PathLossModel", "PathLossOptions", "PathLossProfile", "PathLossSpec",
    "PathlossName", "RMaAV", "TwoRay", "UMaAV", "UMiAV", "check_name", "free_space_loss_db", "get_profile",
    "help_text", "make_pathloss", "names", "register", "spec", "specs",
]
