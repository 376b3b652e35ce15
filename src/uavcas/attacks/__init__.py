"""Attack families, one module each, registered by name (see `base.AttackFamily`).

Adding a family: its name and class string in `uavcas.vocabulary`, and one module here defining
an `@register`ed `AttackFamily` subclass with its spec (plus its tests). Every module of this
package is imported below, so nothing else needs editing.
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
