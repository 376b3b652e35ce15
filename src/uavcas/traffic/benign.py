"""Benign traffic of a run: the apps of the scenario's payload (`plan.scenario.payload`, the
table `payloads.PAYLOADS`; a hand-made plan without a scenario gets `image`), driven in the
row's order and known to this module only through `base.TrafficApp`.

`BenignTraffic.start_servers()` runs before t0 (servers must be listening when the clock
starts); `start_clients(t0)` right at t0; `stop()` at the end, returning run.json's
`http_clients`; `streams_summary()` then gives run.json's `streams` (one section per app that
has one, by app name; None when no app of the payload has one).
"""

from __future__ import annotations

import signal
from pathlib import Path
from typing import Any

from uavcas.twin.model import Plan

from .apps import payload_apps
from .base import AppContext, AppOptions, Hosts, TrafficApp
from .payloads import DEFAULT_PAYLOAD


class BenignTraffic:
    def __init__(self, emu: Hosts | None, plan: Plan, work_dir: Path, duration_s: float, *,
                 options: AppOptions = AppOptions()) -> None:
        self.payload = plan.scenario.payload if plan.scenario is not None else DEFAULT_PAYLOAD
        self.ctx = AppContext(emu, plan, work_dir, duration_s, options)
        self.apps: list[TrafficApp] = [cls(self.ctx) for cls in payload_apps(self.payload)]

    @property
    def mavlink_signed(self) -> bool:
        """MAVLink 2 signing is on and some app of the payload carries MAVLink (run.json)."""
        return self.ctx.options.mavlink_signing and any(a.carries_mavlink for a in self.apps)

    def start_servers(self) -> None:
        for a in self.apps:
            a.start_servers()

    def start_clients(self, t0_unix: float) -> None:
        for a in self.apps:
            a.start_clients(t0_unix)

    def stop(self) -> list[dict[str, Any]]:
        # every app's early processes first (no fetch starts against a stopping server), then the
        # rest; every process of a group is signalled before any is waited for, so they wind down together
        for group in ([p for a in self.apps for p in a.early], [p for a in self.apps for p in a.procs]):
            for p in group:
                if p.popen.poll() is None:
                    try:
                        p.popen.send_signal(signal.SIGTERM)
                    except ProcessLookupError:
                        pass
            for p in group:
                p.stop(signal.SIGTERM, grace_s=2.0)
        return self.summary()

    def streams_summary(self) -> dict[str, Any] | None:
        """What the apps did (run.json `streams`), from their own logs, by app name."""
        out = {a.name: s for a in self.apps if (s := a.streams()) is not None}
        return out or None

    def summary(self) -> list[dict[str, Any]]:
        """run.json `http_clients`: every app's client rows."""
        return [row for a in self.apps for row in a.client_summaries()]
