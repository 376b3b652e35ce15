"""SYN floods: DoS (one attacker) and DDoS (two or more attackers on one victim).

- token `dos=<interval_us>` / `ddos=<interval_us>`: hping3's inter-packet interval, 1000 us ~
  1,000 SYN/s nominal per attacker;
- schedule: DoS takes one attacker; DDoS 2 up to a third of the swarm (at most 4);
- executor: one `emulation.apps.flood.Flood` (hping3 -S to the victim's HTTP port) per
  attacker, its rate calibrated one second in and then periodically; at stop one `rate` record
  per attacker with the measured SYN rate;
- truth (effect `flood`, label source "flood-packets"): a TCP packet with SYN set and ACK clear
  from an attacker IP to a victim IP captured inside [start, stop) of the attack (packet-exact:
  the same host pair outside the window, or the victim's answering SYN-ACKs, are not flood).
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any, Literal

import numpy as np
from pydantic import Field

from .base import AttackFamily, ScenarioError, ScheduleDraw, SpecBase, int_field
from .registry import register

if TYPE_CHECKING:
    from uavcas.emulation.attacks import AttackExecutor
    from uavcas.labels.attacklog import AttackWindow
    from uavcas.labels.effects import TruthContext
    from uavcas.twin.model import Attack

TCP_SYN, TCP_ACK = 0x02, 0x10
DEFAULT_INTERVAL_US = 1000


class FloodSpec(SpecBase):
    family: Literal["dos", "ddos"]
    interval_us: int = Field(gt=0)  # hping3 inter-packet interval: 1000 us ~ 1,000 SYN/s nominal

    @property
    def nominal_pps(self) -> float:
        return 1e6 / self.interval_us

    def token(self) -> str:
        return f"{self.family}={self.interval_us}"


class _Flood(AttackFamily):
    spec = FloodSpec
    label_source = "flood-packets"
    effect = "flood"
    truth_rule = "a TCP SYN (ACK clear) from an attacker to the victim captured inside [start, stop)"
    tools = ("hping3",)
    routes_attack_traffic = True

    @property
    def usage(self) -> str:  # type: ignore[override]
        return f"{self.name}=<us>"

    def parse(self, arg: str | None, tok: str) -> FloodSpec:
        if arg is None:
            raise ScenarioError(f"field 'attacks': {self.name} needs an interval in us, e.g. {self.name}=1000")
        return FloodSpec(family=self.name, interval_us=int_field(f"attacks.{self.name}", arg, 1, 10_000_000))

    def spec_from_params(self, params: dict[str, Any]) -> FloodSpec:
        if "interval_us" in params:
            return FloodSpec(family=self.name, interval_us=int(params["interval_us"]))
        pps = params.get("nominal_pps")
        return FloodSpec(family=self.name, interval_us=round(1e6 / float(pps)) if pps else DEFAULT_INTERVAL_US)

    def params(self, spec: FloodSpec) -> dict[str, float | int | str]:  # type: ignore[override]
        return {**spec.model_dump(exclude={"family"}), "nominal_pps": spec.nominal_pps}

    # executor ----------------------------------------------------------------------------------
    def calibration_times(self, attack: "Attack") -> list[float]:
        from uavcas.emulation.apps.flood import CALIBRATE_AFTER_S, CALIBRATE_EVERY_S

        out, t = [], attack.start_s + CALIBRATE_AFTER_S
        while t < attack.stop_s - 0.5:
            out.append(t)
            t += CALIBRATE_EVERY_S
        return out

    def start(self, ex: "AttackExecutor", attack: "Attack") -> dict[str, Any]:
        from uavcas.emulation.apps.flood import Flood

        nominal = ex.spec(attack).nominal_pps
        floods = [Flood(ex.emu, attack.attack_id, x, ex.ip(v), nominal, ex.log_dir, ex.duration_s + 10)
                  for x in attack.attackers for v in attack.victims]
        ex.state[attack.attack_id] = floods
        for f in floods:
            f.start()
        return {"hping_interval_us": [f.interval_us for f in floods]}

    def calibrate(self, ex: "AttackExecutor", attack: "Attack") -> None:
        for f in ex.state.get(attack.attack_id, []):
            try:
                f.calibrate()
            except Exception as e:  # the flood keeps running at its first interval
                ex.errors.append(f"{attack.attack_id}/{f.attacker}: calibration failed: {e}")

    def stop(self, ex: "AttackExecutor", attack: "Attack") -> dict[str, Any]:
        from uavcas.events import AttackRate

        results = [f.stop() for f in ex.state.pop(attack.attack_id, [])]
        t = ex.now()
        for r in results:
            ex.log(AttackRate(attack_id=attack.attack_id, family=attack.family, attacker=r.attacker,
                              measured_pps=round(r.measured_pps, 2), nominal_pps=r.nominal_pps,
                              hping_interval_us=r.hping_interval_us, syn_count=r.syn_count,
                              seconds=round(r.seconds, 4), restarts=r.restarts, intervals_us=r.intervals_us,
                              victim_ip=r.victim_ip, t_unix=t))
        return {"syn_count": sum(r.syn_count for r in results)}

    # ground truth ------------------------------------------------------------------------------
    def effects(self, ctx: "TruthContext", windows: list["AttackWindow"]) -> np.ndarray:
        p = ctx.packets
        syn_only = (p["proto"] == 6) & ((p["tcp_flags"] & (TCP_SYN | TCP_ACK)) == TCP_SYN)
        hit = np.zeros(ctx.n, dtype=bool)
        for w in windows:
            hit |= (syn_only & ctx.during(w.start_unix, w.stop_unix)
                    & ctx.packets_from(w.attacker_ips) & ctx.packets_to(w.victim_ips))
        return ctx.spread(hit)


@register
class DoS(_Flood):
    name = "dos"


@register
class DDoS(_Flood):
    name = "ddos"
    min_uavs = 3  # 2 attackers + 1 victim

    def attackers(self, spec: FloodSpec, draw: ScheduleDraw) -> list[str]:  # type: ignore[override]
        hi = max(2, min(4, (draw.n_uav - 1) // 3))
        return draw.take(int(draw.rng.integers(2, hi + 1)))
