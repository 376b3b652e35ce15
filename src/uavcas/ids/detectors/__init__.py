"""IDS detectors, one module each, registered by name (see `spec.DetectorSpec`).

Adding a detector: one module here that calls `register(DetectorSpec(...))` (plus its tests).
Every module of this package is imported below, so the CLI's `--models` choices and help, the
benchmark's lists and the leaderboard's order all see it; nothing else needs editing.
Each module imports its estimator library at module level; only torch (the optional `dl` extra)
waits until a deep detector is built (its factory imports `uavcas.ids.nets`).
"""

from __future__ import annotations

import importlib
import pkgutil

from .registry import baseline, baselines, detector, detectors, make_model, names, register
from .spec import KIND_NEEDS, KINDS, DetectorSpec

_INFRA = {"registry", "spec"}  # shared code, no detector
for _m in pkgutil.iter_modules(__path__):
    if _m.name not in _INFRA:
        importlib.import_module(f"{__name__}.{_m.name}")

__all__ = ["KINDS", "KIND_NEEDS", "DetectorSpec", "baseline", "baselines", "detector", "detectors", "make_model",
           "names", "register"]
