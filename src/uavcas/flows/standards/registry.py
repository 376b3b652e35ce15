"""The one registry of feature standards: name -> the standard's record."""

from __future__ import annotations

from .base import FeatureStandard

_REGISTRY: dict[str, FeatureStandard] = {}
# A dataset's standard when none is named (and of files written before standards were recorded):
# CICFlowMeter's definitions, so that the values compare with CICIDS2017-style data.
DEFAULT_STANDARD = "cic"


def register(std: FeatureStandard) -> FeatureStandard:
    """Make `std` the standard of its name; a module calls it once at import."""
    if std.name in _REGISTRY:
        raise ValueError(f"feature standard {std.name!r} registered twice")
    _REGISTRY[std.name] = std
    return std


def names() -> tuple[str, ...]:
    """Every registered standard's name, in the package's module order."""
    return tuple(_REGISTRY)


def standards() -> tuple[FeatureStandard, ...]:
    return tuple(_REGISTRY.values())


def standard(name: str) -> FeatureStandard:
    """The standard called `name`; an unknown name is a one-line ValueError listing the known."""
    try:
        return _REGISTRY[name]
    except (KeyError, TypeError):
        raise ValueError(f"unknown feature standard {name!r}; known: {', '.join(_REGISTRY)}") from None


def feature_columns(name: str = DEFAULT_STANDARD) -> tuple[str, ...]:
    """The feature columns of standard `name`, in stored order."""
    return standard(name).columns


def episode_feature_columns(name: str = DEFAULT_STANDARD) -> tuple[str, ...]:
    """The window-host view's feature columns when its flows follow standard `name`."""
    return standard(name).episode_columns
