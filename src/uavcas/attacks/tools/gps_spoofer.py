"""The GPS spoofer's side of the `gps_spoof` attack: it publishes what the victim's receiver believes.

The receiver model and its control file are the autopilot's (`uavcas.traffic.mavlink.gps`:
`Spoofing`, `control_path`, `GpsReceiver`). The spoofer writes the attack's [start, stop) there,
both boundaries LEAD_S ahead of the moment it writes them (atomically: a temporary file renamed
onto the control file), and the executor logs exactly those times as the attack's start and stop
(`publish`). The receiver decides each fix with the same clock and the same numbers, and a fix
due less than GUARD_S before a boundary waits for it, so the logged [start, stop) and the spoofed
reports agree report for report.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from pathlib import Path

from uavcas.traffic.mavlink.gps import GUARD_S, Spoofing

LEAD_S = 0.1  # a boundary is published this far ahead (an atomic rename takes ~0.1 ms)
PUBLISH_TRIES = 5


def publish(paths: list[Path], make: Callable[[float], Spoofing]) -> float:
    """Write `make(t)` to every path (atomically), t = LEAD_S from now, and return t once every
    file is in place at least GUARD_S before it (else again with a later t): the time to log."""
    for _ in range(PUBLISH_TRIES):
        t = time.time() + LEAD_S
        text = make(t).model_dump_json()
        for path in paths:
            path.parent.mkdir(parents=True, exist_ok=True)
            tmp = path.with_suffix(".tmp")
            tmp.write_text(text)
            tmp.replace(path)
        if time.time() <= t - GUARD_S:
            return t
    raise TimeoutError(f"could not publish the spoofer's times {LEAD_S:g} s ahead ({PUBLISH_TRIES} tries)")
