"""The one registry of traffic apps: app name -> `TrafficApp` class.

An app module calls `register` on its class; `uavcas.traffic.apps` imports every app module, so
read the registry through that package (importing this module alone registers nothing). The
payload table (`payloads.PAYLOADS`) names apps by these names.
"""

from __future__ import annotations

import re

from .base import TrafficApp
from .payloads import PAYLOADS, apps_of

_REGISTRY: dict[str, type[TrafficApp]] = {}
_TOKEN = re.compile(r"^[a-z0-9_]+$")


def register(cls: type[TrafficApp]) -> type[TrafficApp]:
    """Make `cls` the app of its name (a class decorator of an app module)."""
    if not (isinstance(cls, type) and issubclass(cls, TrafficApp)):
        raise TypeError(f"{cls!r} is not a TrafficApp")
    name = getattr(cls, "name", None)
    if not isinstance(name, str) or not _TOKEN.match(name):
        raise ValueError(f"traffic app {cls.__name__}: name {name!r} must match {_TOKEN.pattern}")
    if name in _REGISTRY:
        raise ValueError(f"traffic app {name!r} registered twice")
    if not isinstance(cls.carries_mavlink, bool):
        raise ValueError(f"traffic app {name!r}: carries_mavlink must be a bool")
    _REGISTRY[name] = cls
    return cls


def names() -> tuple[str, ...]:
    """Every registered app, in registration order."""
    return tuple(_REGISTRY)


def app(name: str) -> type[TrafficApp]:
    try:
        return _REGISTRY[name]
    except KeyError:
        raise ValueError(f"unknown traffic app {name!r}; registered: {', '.join(_REGISTRY)}") from None


def payload_apps(payload: str) -> tuple[type[TrafficApp], ...]:
    """The app classes of a payload, in the row's order (a one-line ValueError for an unknown
    payload or app)."""
    return tuple(app(a) for a in apps_of(payload))


def carries_mavlink(payload: str) -> bool:
    return any(cls.carries_mavlink for cls in payload_apps(payload))


def unregistered() -> dict[str, tuple[str, ...]]:
    """Per payload, the apps its row names that no module registers (empty: the table is whole)."""
    out = {p: tuple(a for a in row if a not in _REGISTRY) for p, row in PAYLOADS.items()}
    return {p: missing for p, missing in out.items() if missing}
