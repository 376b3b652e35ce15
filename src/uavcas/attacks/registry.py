"""The one registry of attack families: name -> the family's (single) instance."""

from __future__ import annotations

from uavcas.vocabulary import FAMILIES

from .base import AttackFamily

_REGISTRY: dict[str, AttackFamily] = {}


def register(cls: type[AttackFamily]) -> type[AttackFamily]:
    """Class decorator: make `cls` the family of its `name` (a vocabulary family)."""
    if cls.name not in FAMILIES:
        raise ValueError(f"attack family {cls.name!r} has no row in uavcas.vocabulary.ROWS")
    if cls.name in _REGISTRY:
        raise ValueError(f"attack family {cls.name!r} registered twice")
    _REGISTRY[cls.name] = cls()
    return cls


def family(name: str) -> AttackFamily:
    try:
        return _REGISTRY[name]
    except KeyError:
        raise KeyError(f"unknown attack family {name!r}; known: {', '.join(FAMILIES)}") from None


def families() -> tuple[AttackFamily, ...]:
    """Every family, in canonical (vocabulary) order."""
    return tuple(_REGISTRY[f] for f in FAMILIES if f in _REGISTRY)
