"""The one registry of path-loss models: scenario name -> `PathLossSpec`.

The scenario codec, `Scenario.pathloss`, the `uavcas channel predict --model` choices and help,
and the data dictionary all read `names()` / `specs()`; no other list of the names exists.
"""

from __future__ import annotations

import re
from typing import Annotated

from pydantic import AfterValidator

from .base import PathLossModel, PathLossOptions, PathLossSpec

_REGISTRY: dict[str, PathLossSpec] = {}
_TOKEN = re.compile(r"^[a-z0-9_]+$")  # a scenario field: no '-' (the separator), no '+' or '='


def register(spec: PathLossSpec) -> PathLossSpec:
    """Make `spec` the model of its name; a model module calls this once per name it offers."""
    if not _TOKEN.match(spec.name):
        raise ValueError(f"path-loss model name {spec.name!r} must match {_TOKEN.pattern}")
    if spec.name in _REGISTRY:
        raise ValueError(f"path-loss model {spec.name!r} registered twice")
    if not isinstance(getattr(spec.model, "samples_los", None), bool):
        raise ValueError(f"path-loss model {spec.name!r}: {spec.model.__name__}.samples_los must be a bool")
    _REGISTRY[spec.name] = spec
    return spec


def names() -> tuple[str, ...]:
    """Every registered name, in registration order (module order, then the order inside one)."""
    return tuple(_REGISTRY)


def specs() -> tuple[PathLossSpec, ...]:
    return tuple(_REGISTRY.values())


def _unknown(name: object) -> str:
    return f"unknown path-loss model {name!r}; registered: {', '.join(_REGISTRY)}"


def spec(name: str) -> PathLossSpec:
    try:
        return _REGISTRY[name]
    except KeyError:
        raise ValueError(_unknown(name)) from None


def check_name(name: str) -> str:
    """`name` if registered, else a one-line ValueError listing the registered names."""
    if name not in _REGISTRY:
        raise ValueError(_unknown(name))
    return name


# A scenario's path-loss field: a str checked against the registry when the model is validated.
PathlossName = Annotated[str, AfterValidator(check_name)]


def make_pathloss(name: str, profile=None, fc_ghz: float | None = None, h_bs_m: float | None = None) -> PathLossModel:
    """The model of a registered name at carrier `fc_ghz` (None: 3.51 GHz, or the log-distance
    profile's own carrier). `profile` applies to log-distance only (default ``paper-anchored``);
    `h_bs_m` overrides a model's default BS height (used only where no geometry gives one)."""
    return spec(name).build(PathLossOptions(profile=profile, fc_ghz=fc_ghz, h_bs_m=h_bs_m))


def help_text() -> str:
    """The models as "name: summary; ..." for the CLI's help (the standards are in `specs()`)."""
    return "; ".join(f"{s.name}: {s.summary}" for s in _REGISTRY.values())
