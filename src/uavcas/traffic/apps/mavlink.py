"""The `mavlink` app: MAVLink v2 between every UAV's autopilot and its BS's ground station
(`uavcas.traffic.mavlink`, pymavlink): one endpoint process per node, loaded and bound before
t0, each waiting for t0 (a file written at t0) and then running the plan's windows. A UAV's
autopilot keeps sending while the plan has it disconnected, as a radio would.
"""

from __future__ import annotations

import sys
from collections import Counter
from typing import Any, ClassVar

from uavcas.emulation.apps.procs import spawn, wait_for
from uavcas.traffic import mavlink

from ..base import APP_OVERRUN_S, AppContext, TrafficApp
from ..registry import register

MAVLINK_READY_S = 120.0  # loading Python + pymavlink in every namespace at once takes seconds
MAVLINK_GRACE_S = 10.0  # the endpoints' own deadline is the run's end; `timeout` kills them this much later
ENDPOINT_MODULE = "uavcas.traffic.mavlink"  # run as `python -m ENDPOINT_MODULE {uav|gcs} SPEC.json`


@register
class MavlinkApp(TrafficApp):
    name: ClassVar[str] = "mavlink"
    summary: ClassVar[str] = "an autopilot per UAV and a ground station per BS on UDP 14550 (MAVLink v2)"
    carries_mavlink: ClassVar[bool] = True

    def __init__(self, ctx: AppContext) -> None:
        super().__init__(ctx)
        self.t0_path = ctx.work_dir / "mavlink" / "t0"
        # MAVLink 2 signing on both ends, with the run's key (mavlink/signing.py); never the attacker's
        self.signing = (mavlink.signing_spec(ctx.plan.seed, ctx.plan.config) if ctx.options.mavlink_signing
                        else None)

    def start_servers(self) -> None:
        """A ground station per BS and an autopilot per UAV, loaded and bound before t0; each waits
        for t0 (`t0_path`, written by start_clients) and then runs the plan's windows."""
        ctx, plan = self.ctx, self.ctx.plan
        spec_dir = ctx.work_dir / "mavlink"
        spec_dir.mkdir(parents=True, exist_ok=True)
        self.t0_path.unlink(missing_ok=True)
        run = [sys.executable, "-m", ENDPOINT_MODULE]
        app_s = ctx.duration_s + APP_OVERRUN_S
        timeout_s = mavlink.T0_WAIT_S + app_s + MAVLINK_GRACE_S
        # the rate is the plan's (plan.json records it); the options keep the GCS's other settings
        rates = ctx.options.stream_rates.model_copy(update={"stream_rate_hz": plan.mavlink_stream_hz})
        for b in ctx.bss:
            if b.sysid is None:
                raise ValueError(f"{b.name} has no MAVLink system id in the plan")
            served = [mavlink.gcs_target(plan, uav) for bs, uav in ctx.pairs if bs == b.name]
            spec = mavlink.GcsSpec(name=b.name, sysid=b.sysid, rates=rates, uavs=served,
                                   signing=self.signing,
                                   t0_path=self.t0_path, window_s=plan.window_s,
                                   n_windows=len(plan.windows), duration_s=app_s,
                                   log_path=ctx.log_dir / f"mavlink-{b.name}.jsonl")
            path = spec_dir / f"{b.name}.json"
            path.write_text(spec.model_dump_json())
            self.procs.append(spawn(ctx.starter(b.name), f"mavlink-{b.name}", run + ["gcs", str(path)],
                                    ctx.log_dir, timeout_s))
        for bs, uav in ctx.pairs:
            spec = mavlink.uav_spec(plan, uav, plan.node(bs).ip, None, app_s,
                                    ctx.log_dir / f"mavlink-{uav}.jsonl", t0_path=self.t0_path,
                                    signing=self.signing, gps_path=mavlink.gps.control_path(ctx.work_dir, uav),
                                    radio=mavlink.radio_spec(plan, uav, rates))
            path = spec_dir / f"{uav}.json"
            path.write_text(spec.model_dump_json())
            self.procs.append(spawn(ctx.starter(uav), f"mavlink-{uav}", run + ["uav", str(path)],
                                    ctx.log_dir, timeout_s))

        def ready() -> bool:  # every endpoint bound and waiting for t0
            return all(p.stdout().startswith("ready") for p in self.procs)

        if not wait_for(ready, MAVLINK_READY_S, 0.05):
            bad = [p for p in self.procs if not p.stdout().startswith("ready")]
            why = bad[0].stderr().strip()[-300:] or "not ready"
            raise RuntimeError(f"MAVLink endpoint {bad[0].name} did not start: {why}")

    def start_clients(self, t0_unix: float) -> None:
        mavlink.write_t0(self.t0_path, t0_unix)  # the endpoints, loaded before t0, start now

    def streams(self) -> dict[str, Any]:
        """Per ground station: the UAVs whose mission it uploaded, its commands' outcomes and, per
        UAV, the messages it received by type (from its own log)."""
        out: dict[str, Any] = {}
        for b in self.ctx.bss:
            path = self.ctx.log_dir / f"mavlink-{b.name}.jsonl"
            lines = mavlink.read_log(path) if path.exists() else []
            summary = next((e for e in reversed(lines) if e.get("event") == "summary"), None)
            results = Counter(e.get("result", "?") for e in lines if e.get("event") == "command_result")
            out[b.name] = {
                "uploaded": summary["uploaded"] if summary else None,
                "commands": dict(results),
                "received_by_uav": summary["received_by_uav"] if summary else None}
        return out
