"""The traffic apps, one module each (see `uavcas.traffic.base.TrafficApp`), all registered on
import of this package: `image` (nginx + curl fetches), `mavlink` (autopilot and ground-station
endpoints), `video` (H.264 over RTP to a sink per BS).

Adding an app: one module here defining a `TrafficApp` subclass decorated with
`uavcas.traffic.registry.register`, plus a row naming it in `uavcas.traffic.payloads.PAYLOADS`
(a new payload) or its name added to a row; plus its tests. The scenario codec, the planner and
the runner then offer it with no further edit (tests/traffic/test_traffic_dropin.py).
"""

from __future__ import annotations

import importlib
import pkgutil

from ..payloads import PAYLOADS
from ..registry import app, carries_mavlink, names, payload_apps, register, unregistered

for _m in pkgutil.iter_modules(__path__):
    importlib.import_module(f"{__name__}.{_m.name}")

# The payloads one of whose apps carries MAVLink (the MAVLink attacks need one; --mavlink-signing too).
MAVLINK_PAYLOADS: tuple[str, ...] = tuple(p for p, row in PAYLOADS.items()
                                          if any(a in names() and app(a).carries_mavlink for a in row))

__all__ = ["MAVLINK_PAYLOADS", "app", "carries_mavlink", "names", "payload_apps", "register", "unregistered"]
