"""SYN floods: DoS (one attacker) and DDoS (two or more attackers on one victim).

- token `dos=<interval_us>` / `ddos=<interval_us>`: hping3's inter-packet interval, 1000 us ~
  1,000 SYN/s nominal per attacker;
- schedule: DoS takes one attacker; DDoS 2 up to a third of the swarm (at most 4);
- executor: one `attacks.tools.flood.Flood` per attacker: one hping3 (-S to the victim's
  HTTP port) for the whole attack, started before t0 behind a closed gate and paced from
  outside at the nominal rate (see that module); the start is logged when the gates are open
  and before the first SYN, the stop when the gates closed (no SYN leaves after it), with
  `crossed_unix`, when its last SYN can have crossed the network; at stop one `rate` record per
  attacker with the SYNs that left it. [start, stop) is thus when the attack sent: its rate over
  the logged window is its sending rate (issue 28, item 5);
- truth (effect `flood`, label source "flood-packets"): a TCP packet with SYN set and ACK clear
  from an attacker IP to a victim IP captured inside [start, crossed) of the attack (packet-exact:
  the same host pair outside the window, or the victim's answering SYN-ACKs, are not flood);
- provoked (effect `provoked` with this family): what exists only because of a flood SYN,
  matched to that SYN packet to packet (`attacks.answers`), within ANSWER_WITHIN_S after it and
  not gated by the window's stop (the victim retransmits its SYN-ACKs for 31 s):
  (a) the victim's SYN-ACKs on the SYN's 5-tuple reversed whose ack is the SYN's seq + 1
      (mod 2^32), retransmissions included (they repeat seq and ack);
  (b) the RST answering them: from the SYN's source to the victim on the SYN's 5-tuple with RST
      set and seq = the SYN's seq + 1 (the attacker's kernel, which never sent the SYN, answers
      the unexpected SYN-ACK with RST, seq = that SYN-ACK's ack; RFC 793);
  (c) ICMP errors to the SYN's source that quote it (protocol, addresses, ports, seq).
  A benign connection between the same hosts has its own ports and seq: it stays benign.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING, Any, ClassVar, Literal

import numpy as np
from pydantic import Field

from uavcas.events import AttackRate
from uavcas.scenario_model import ScenarioError, SpecBase, int_field

from .answers import ANSWER_WITHIN_S, TCP_ACK, TCP_RST, TCP_SYN, answers, icmp_errors_quoting, tcp_flags_are
from .base import AttackExecutor, AttackFamily, ScheduleDraw, SyntheticPackets, TruthContext
from .registry import register
from .tools.flood import Flood, close_all, collect_all, quiet_after_s, start_all

if TYPE_CHECKING:  # types only: the twin's and labels' package __init__s load this registry
    from uavcas.labels.attacklog import AttackWindow
    from uavcas.twin.model import Attack

DEFAULT_INTERVAL_US = 1000


class FloodSpec(SpecBase):
    family: Literal["dos", "ddos"]
    interval_us: int = Field(gt=0)  # hping3 inter-packet interval: 1000 us ~ 1,000 SYN/s nominal

    @property
    def nominal_pps(self) -> float:
        return 1e6 / self.interval_us

    def token(self) -> str:
        return f"{self.family}={self.interval_us}"


def path_hops(ex: "AttackExecutor", src: str, dst: str) -> list[tuple[float, float]]:
    """(delay_ms, rate_mbps) of each link a frame from src to dst crosses now ([] if dropped)."""
    fwd, w = ex.emu.forwarding, ex.window
    path = fwd.path(src, dst) if fwd is not None else None
    if not path or w is None:
        return []
    links = {frozenset((lk.a, lk.b)): lk for lk in w.links}
    return [(links[frozenset(h)].delay_ms, links[frozenset(h)].rate_mbps) for h in zip(path, path[1:])
            if frozenset(h) in links]


class _Flood(AttackFamily):
    spec = FloodSpec
    truth_rule = "a TCP SYN (ACK clear) from an attacker to the victim captured inside [start, stop)"
    provoked_rule = ("the victim's SYN-ACKs (retransmissions included) on a flood SYN's 5-tuple reversed with "
                     "ack = its seq + 1; the RST from the SYN's source on its 5-tuple with seq = its seq + 1; "
                     "ICMP errors quoting the SYN; each within "
                     f"{ANSWER_WITHIN_S:g} s after the SYN, even after the attack's stop")
    tools = ("hping3",)
    routes_attack_traffic = True
    exclusive_group = "flood"

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
    def prepare(self, ex: "AttackExecutor", attack: "Attack") -> None:
        nominal = ex.spec(attack).nominal_pps
        floods = [Flood(ex.emu, attack.attack_id, x, ex.ip(v), nominal, ex.log_dir, ex.duration_s + 30)
                  for x in attack.attackers for v in attack.victims]
        ex.state[attack.attack_id] = floods
        for f in floods:
            for proc in f.prepare():
                ex.add_process(proc)

    def start(self, ex: "AttackExecutor", attack: "Attack") -> dict[str, Any]:
        floods = ex.state[attack.attack_id]
        t = start_all(floods)  # every gate open, no SYN paced yet: the first one can go from t on
        return {"t_unix": t, "hping_interval_us": [f.interval_us for f in floods]}

    def stop(self, ex: "AttackExecutor", attack: "Attack") -> dict[str, Any]:
        return self.halt(ex, attack)()

    def halt(self, ex: "AttackExecutor", attack: "Attack") -> Callable[[], dict[str, Any]]:
        floods = ex.state.pop(attack.attack_id, [])
        t_closed = close_all(floods)

        def finish() -> dict[str, Any]:
            results = collect_all(floods)
            # no SYN left an attacker after t_closed; the last ones may still be crossing the network
            quiet = max((quiet_after_s(path_hops(ex, x, v)) for x in attack.attackers for v in attack.victims),
                        default=0.0)
            for r in results:
                ex.log(AttackRate(attack_id=attack.attack_id, family=attack.family, attacker=r.attacker,
                                  measured_pps=round(r.measured_pps, 2), nominal_pps=r.nominal_pps,
                                  hping_interval_us=r.interval_us, syn_count=r.syn_count,
                                  seconds=round(r.seconds, 4), restarts=0, intervals_us=[r.interval_us],
                                  victim_ip=r.victim_ip, t_unix=t_closed))
            return {"t_unix": t_closed, "crossed_unix": t_closed + quiet,
                    "syn_count": sum(r.syn_count for r in results)}

        return finish

    # ground truth ------------------------------------------------------------------------------
    def effects(self, ctx: "TruthContext", windows: list["AttackWindow"]) -> np.ndarray:
        p = ctx.packets
        syn_only = (p["proto"] == 6) & ((p["tcp_flags"] & (TCP_SYN | TCP_ACK)) == TCP_SYN)
        return ctx.spread(ctx.attacker_to_victim(windows, syn_only))

    def provoked(self, ctx: "TruthContext", windows: list["AttackWindow"], made: np.ndarray) -> np.ndarray:
        p = ctx.packets
        syn = made & tcp_flags_are(p, TCP_SYN, TCP_SYN | TCP_ACK)  # the flood SYNs (module docstring)
        next_seq = p["tcp_seq"].astype(np.int64) + 1
        synack = tcp_flags_are(p, TCP_SYN | TCP_ACK, TCP_SYN | TCP_ACK | TCP_RST)
        rst = tcp_flags_are(p, TCP_RST, TCP_RST)
        hit = (answers(p, syn, synack, reverse=True, field="tcp_ack", value=next_seq[syn])
               | answers(p, syn, rst, reverse=False, field="tcp_seq", value=next_seq[syn])
               | icmp_errors_quoting(p, syn))
        return ctx.spread(hit) & ~made

    # synthetic flows ---------------------------------------------------------------------------
    synthetic_pps: ClassVar[float] = 1000.0  # the synthetic flood's mean rate, SYN/s

    def synthetic_packets(self, rng: np.random.Generator) -> SyntheticPackets:
        """A separable SYN flood: 100-600 SYNs of 54-74 B at ~`synthetic_pps`, a few RST+ACK answers
        (whatever other family the class holds: one flood makes the flow)."""
        n = int(rng.integers(100, 600))
        mean = 1.0 / self.synthetic_pps * rng.lognormal(0, 0.4)
        t = np.concatenate([[0.0], np.cumsum(rng.exponential(mean, n - 1))])
        d = (rng.random(n) < 0.05).astype(np.int8)  # a few RST answers
        d[0] = 0  # the attacker's SYN opens the flow
        size = np.where(d == 0, rng.integers(54, 75, n), 54)
        flags = np.where(d == 0, TCP_SYN, TCP_RST | TCP_ACK).astype(np.int16)
        return t, size, d, flags


@register
class DoS(_Flood):
    name = "dos"


@register
class DDoS(_Flood):
    name = "ddos"
    min_uavs = 3  # 2 attackers + 1 victim
    synthetic_pps = 2000.0  # two or more attackers on one victim

    def attackers(self, spec: FloodSpec, draw: ScheduleDraw) -> list[str]:  # type: ignore[override]
        hi = max(2, min(4, (draw.n_uav - 1) // 3))
        return draw.take(int(draw.rng.integers(2, hi + 1)))
