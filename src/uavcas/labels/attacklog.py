"""The ground truth of one run, typed: attack windows and replay injections.

Read from RUN_DIR/attacks.jsonl through the `uavcas.events` records (authoritative: epoch times of the capture clock,
see docs/formats.md). An attack of the plan with no `start` record in the log (e.g. a run that crashed
before logging it) falls back to the plan: start/stop = run.json `t0_unix` + plan `start_s`/`stop_s`
and the IPs of the plan's nodes; such windows carry `from_plan=True`. A `start` without `stop`
lasts until +inf (the end of the capture).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path

from uavcas.events import AttackStart, AttackStop, Inject, RecordError, read_attack_records
from uavcas.twin.model import Plan


class LabelError(ValueError):
    """Malformed ground truth; the message names the file (and line) at fault."""


@dataclass(frozen=True)
class AttackWindow:
    attack_id: str
    family: str
    attacker_ips: tuple[str, ...]
    victim_ips: tuple[str, ...]
    start_unix: float
    stop_unix: float  # exclusive: the attack acts no more from here
    from_plan: bool = False
    crossed_unix: float | None = None  # when its last packet can have crossed the network (AttackStop)

    @property
    def observed_until_unix(self) -> float:
        """The end of the span holding every observation of the attack's packets (exclusive)."""
        return self.stop_unix if self.crossed_unix is None else max(self.stop_unix, self.crossed_unix)


@dataclass(frozen=True)
class Injection:
    attack_id: str
    t_unix: float
    src_ip: str
    dst_ip: str
    protocol: int
    ip_id: int
    ttl: int
    seq: int | None
    # the copy's transport ports (TCP/UDP), None when the record has none: for UDP, which has no
    # sequence number, they are what tells two streams of one host pair apart
    src_port: int | None = None
    dst_port: int | None = None


@dataclass(frozen=True)
class AttackLog:
    windows: tuple[AttackWindow, ...] = ()
    injections: tuple[Injection, ...] = field(default_factory=tuple)

    def of_family(self, *families: str) -> list[AttackWindow]:
        return [w for w in self.windows if w.family in families]


def read_attack_log(path: Path, plan: Plan | None = None, t0_unix: float | None = None) -> AttackLog:
    """Parse attacks.jsonl (may be absent for a benign run) and fill gaps from the plan."""
    starts: dict[str, AttackStart] = {}
    stops: dict[str, AttackStop] = {}
    injections: list[Injection] = []
    try:
        records = read_attack_records(path) if path.exists() else []
    except RecordError as exc:
        raise LabelError(str(exc)) from None
    for rec in records:
        if isinstance(rec, AttackStart):
            starts[rec.attack_id] = rec
        elif isinstance(rec, AttackStop):
            stops[rec.attack_id] = rec
        elif isinstance(rec, Inject):
            injections.append(
                Injection(attack_id=rec.attack_id, t_unix=rec.t_unix, src_ip=rec.src_ip, dst_ip=rec.dst_ip,
                          protocol=rec.protocol, ip_id=rec.ip_id, ttl=rec.ttl, seq=rec.seq,
                          src_port=rec.src_port, dst_port=rec.dst_port)
            )
    windows: list[AttackWindow] = []
    for aid, rec in starts.items():
        attackers = tuple(rec.attacker_ips or _plan_ips(plan, rec.attackers))
        victims = tuple(rec.victim_ips or _plan_ips(plan, rec.victims))
        windows.append(
            AttackWindow(
                attack_id=aid,
                family=rec.family,
                attacker_ips=attackers,
                victim_ips=victims,
                start_unix=rec.t_unix,
                stop_unix=stops[aid].t_unix if aid in stops else math.inf,
                crossed_unix=stops[aid].crossed_unix if aid in stops else None,
            )
        )
    if plan is not None:
        for att in plan.attacks:
            if att.attack_id in starts:
                continue
            if t0_unix is None:
                raise LabelError(
                    f"{path}: attack {att.attack_id} of the plan is not logged and run.json has no t0_unix"
                )
            windows.append(
                AttackWindow(
                    attack_id=att.attack_id,
                    family=att.family,
                    attacker_ips=tuple(_plan_ips(plan, att.attackers)),
                    victim_ips=tuple(_plan_ips(plan, att.victims)),
                    start_unix=t0_unix + att.start_s,
                    stop_unix=t0_unix + att.stop_s,
                    from_plan=True,
                )
            )
    windows.sort(key=lambda w: (w.start_unix, w.attack_id))
    return AttackLog(tuple(windows), tuple(injections))


def _plan_ips(plan: Plan | None, names) -> list[str]:
    if plan is None:
        return []
    out = []
    for name in names:
        try:
            out.append(plan.node(name).ip)
        except KeyError:
            raise LabelError(f"attack log names node {name!r}, which is not in plan.json") from None
    return out
