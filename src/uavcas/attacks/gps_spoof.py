"""GPS spoofing: the victim's GPS receiver believes a spoofer, and its position reports drift to a lure.

- token `gps_spoof=<drift_mps>`: the rate (m/s, > 0, at most two decimals, e.g. `gps_spoof=3`,
  `gps_spoof=0.5`) at which the claimed position moves away from the true one towards a lure
  point. Default DEFAULT_DRIFT_MPS = 3 m/s (plans written without it): below the missions'
  cruise speeds (5-10 m/s, `mobility.params`), so the claimed track stays a plausible multirotor
  flight (no jump, no impossible speed: a spoofer's carry-off must be followed by the receiver's
  own tracking loops), yet over an attack of 10-20 s it carries the claim 30-60 m away, 10 to 20
  times a consumer receiver's ~3 m horizontal error, so the drift is there to be found in the data.
  Only MAVLink payloads carry position reports: the codec refuses the family on `image`;
- schedule: the victim is the composition's; there is no attacker node (the spoofer is a radio
  transmitter near the victim, not a host of the network: `attackers` is empty, min_uavs 1). The
  lure is drawn from the schedule's seeded stream (`drawn_params`): a bearing uniform in
  [0, 360) degrees and a distance uniform in [LURE_MIN_M, LURE_MAX_M] from the victim's planned
  position at the attack's planned start, recorded in the plan as `lure_bearing_deg` and
  `lure_distance_m` (the area's scale: 1 km);
- executor: no network change. `start` publishes the spoofer to the victim's autopilot
  (`attacks.tools.gps_spoofer`: a control file in the run's apps directory that the autopilot's
  receiver reads, `traffic.mavlink.gps`, written atomically with a start time LEAD_S
  ahead, logged as the start), `stop` publishes the stop the same way.
  From its logged start the victim's GLOBAL_POSITION_INT and GPS_RAW_INT report the true track
  plus an offset growing at drift_mps along the lure's bearing (capped at its distance), with the
  matching velocity and course; after its logged stop the receiver re-acquires the true signal.
  The true track keeps driving the channel (the plan is unchanged), so the claimed position and
  the link quality the captures show disagree, as they would in the air;
- truth (effect `gps_spoof`, label source "gps-spoof-reports"): a MAVLink GLOBAL_POSITION_INT
  (id 33) or GPS_RAW_INT (id 24) datagram (`mav_msgid`, decoded from the frame header by
  `uavcas.flows.decode`) from a victim IP whose transmission's first observation (at the victim's
  switch, the capture nearest its sending) lies inside [start, stop). Its other observations carry
  the same effect. Packet-exact: the autopilot decides each report's spoofing at its sending with
  the logged times (see `traffic.mavlink.gps`), and the victim's other messages, or its
  reports outside the window, stay benign;
- provoked: nothing (the default hook). The ground station answers no position report, and
  what a spoofed report changes in a real GCS (a map) sends no packet here.
"""

from __future__ import annotations

import re
from collections.abc import Callable
from typing import TYPE_CHECKING, Any, Literal

import numpy as np
from pydantic import Field
from pymavlink.dialects.v20 import common

from uavcas.scenario_model import ScenarioError, SpecBase
from uavcas.traffic.apps import MAVLINK_PAYLOADS
from uavcas.traffic.mavlink.gps import POSITION_MESSAGES, Spoofing, control_path

from .base import AttackExecutor, AttackFamily, ScheduleDraw, TruthContext
from .registry import register
from .tools.gps_spoofer import publish

if TYPE_CHECKING:  # types only: the twin's and labels' package __init__s load this registry
    from uavcas.labels.attacklog import AttackWindow
    from uavcas.twin.model import Attack

DEFAULT_DRIFT_MPS = 3.0  # module docstring
MAX_DRIFT_MPS = 100.0
LURE_MIN_M, LURE_MAX_M = 200.0, 1000.0
_DRIFT = re.compile(r"^(0|[1-9][0-9]*)(\.[0-9]{1,2})?$")  # the codec then asks for the canonical form


class GpsSpoofSpec(SpecBase):
    family: Literal["gps_spoof"] = "gps_spoof"
    drift_mps: float = Field(gt=0, le=MAX_DRIFT_MPS)  # claimed-minus-true offset growth rate

    def token(self) -> str:
        return f"gps_spoof={_drift_text(self.drift_mps)}"


def _drift_text(v: float) -> str:
    return f"{v:.2f}".rstrip("0").rstrip(".")


@register
class GpsSpoof(AttackFamily):
    name = "gps_spoof"
    spec = GpsSpoofSpec
    usage = "gps_spoof=<drift_mps>"
    truth_rule = ("a MAVLink GLOBAL_POSITION_INT or GPS_RAW_INT datagram from the victim first seen (at its own "
                  "switch) inside [start, stop): a position report of its spoofed GPS receiver")
    provoked_rule = "nothing (the ground station answers no position report)"
    python_modules = ("pymavlink",)
    min_uavs = 1  # the victim; the spoofer is no node of the network
    payloads = MAVLINK_PAYLOADS
    payloads_why = "it acts on the MAVLink position reports, which image traffic does not carry"

    def parse(self, arg: str | None, tok: str) -> GpsSpoofSpec:
        if arg is None:
            raise ScenarioError(f"field 'attacks': gps_spoof needs a drift rate in m/s, e.g. "
                                f"gps_spoof={_drift_text(DEFAULT_DRIFT_MPS)}")
        if not _DRIFT.match(arg) or not 0 < float(arg) <= MAX_DRIFT_MPS:
            raise ScenarioError(f"field 'attacks.gps_spoof': expected a drift rate in m/s in (0, {MAX_DRIFT_MPS:g}] "
                                f"with at most two decimals, got {arg!r}")
        return GpsSpoofSpec(drift_mps=float(arg))

    def spec_from_params(self, params: dict[str, Any]) -> GpsSpoofSpec:
        return GpsSpoofSpec(drift_mps=float(params.get("drift_mps", DEFAULT_DRIFT_MPS)))

    # schedule ----------------------------------------------------------------------------------
    def attackers(self, spec: SpecBase, draw: ScheduleDraw) -> list[str]:
        return []

    def drawn_params(self, spec: SpecBase, draw: ScheduleDraw) -> dict[str, float | int | str]:
        bearing = round(float(draw.rng.uniform(0.0, 360.0)), 1) % 360.0
        distance = round(float(draw.rng.uniform(LURE_MIN_M, LURE_MAX_M)), 1)
        return {"lure_bearing_deg": bearing, "lure_distance_m": distance}

    # executor ----------------------------------------------------------------------------------
    def _control(self, ex: "AttackExecutor", attack: "Attack"):
        s: GpsSpoofSpec = ex.spec(attack)  # type: ignore[assignment]
        paths = [control_path(ex.work_dir, v) for v in attack.victims]
        base = Spoofing(start_unix=0.0, drift_mps=s.drift_mps, bearing_deg=float(attack.params["lure_bearing_deg"]),
                        distance_m=float(attack.params["lure_distance_m"]))
        return paths, base

    def start(self, ex: "AttackExecutor", attack: "Attack") -> dict[str, Any]:
        paths, base = self._control(ex, attack)
        t = publish(paths, lambda t: base.model_copy(update={"start_unix": t}))
        ex.state[attack.attack_id] = t
        return {"t_unix": t}  # the receivers believe the spoofer from exactly this instant

    def stop(self, ex: "AttackExecutor", attack: "Attack") -> dict[str, Any]:
        return self.halt(ex, attack)()

    def halt(self, ex: "AttackExecutor", attack: "Attack") -> Callable[[], dict[str, Any]]:
        paths, base = self._control(ex, attack)
        start = ex.state.pop(attack.attack_id)
        t = publish(paths, lambda t: base.model_copy(update={"start_unix": start, "stop_unix": t}))
        return lambda: {"t_unix": t}  # ... and re-acquire the true signal from exactly this one

    # ground truth ------------------------------------------------------------------------------
    def effects(self, ctx: "TruthContext", windows: list["AttackWindow"]) -> np.ndarray:
        ids = [getattr(common, f"MAVLINK_MSG_ID_{name}") for name in POSITION_MESSAGES]  # 33 and 24
        reports = np.isin(ctx.packets["mav_msgid"], ids)
        hit = np.zeros(ctx.n, dtype=bool)
        for w in windows:
            hit |= reports & ctx.is_first & ctx.packets_from(w.victim_ips) & ctx.during(w.start_unix, w.stop_unix)
        return ctx.spread(hit)
