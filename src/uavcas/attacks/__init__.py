"""Attack families, one module each, registered by name (see `base.AttackFamily`).

Adding a family is one module plus one row: the row in `uavcas.vocabulary.ROWS` (its token, class
string, packet effect and the effect's precedence, label source: every tuple of families, effects
and label sources derives from the table), and one module here defining an `@register`ed
`AttackFamily` subclass (its spec, schedule, executor, truth rules and, optionally, its synthetic
recipe), plus its tests; a tool it runs goes beside it in `tools/`. Every module of this package
but the shared ones (`_INFRA`) is imported below, so nothing else needs editing: the codec, the
planner, the runner, the labeller, the synthetic generator, the dataset card and the CLI ask the
registry and the vocabulary (`tests/attacks/test_family_dropin.py` adds one this way).
"""

from __future__ import annotations

import importlib
import pkgutil

from uavcas.vocabulary import FAMILIES

from .base import (
    AttackExecutor,
    AttackFamily,
    Emitter,
    EmitterContext,
    ScenarioError,
    ScheduleDraw,
    SpecBase,
    SyntheticPackets,
    TruthContext,
)
from .registry import families, family, register

_INFRA = {"answers", "base", "registry", "tools"}  # shared code and the families' tools, no family
for _m in pkgutil.iter_modules(__path__):
    if _m.name not in _INFRA:
        importlib.import_module(f"{__name__}.{_m.name}")

_missing = [f for f in FAMILIES if f not in {fam.name for fam in families()}]
if _missing:
    raise ImportError(f"attack families without a module in uavcas.attacks: {', '.join(_missing)}")

# Distinct spec classes in canonical order (dos and ddos share one).
SPECS: tuple[type[SpecBase], ...] = tuple(dict.fromkeys(f.spec for f in families()))

__all__ = ["AttackExecutor", "AttackFamily", "Emitter", "EmitterContext", "SPECS", "ScenarioError", "ScheduleDraw",
           "SpecBase", "SyntheticPackets", "TruthContext", "families", "family", "register"]
