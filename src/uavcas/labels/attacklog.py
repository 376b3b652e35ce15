"""The ground truth of one run, typed: attack windows and replay injections.

Read from RUN_DIR/attacks.jsonl (authoritative: epoch times of the capture clock, see
docs/formats.md). An attack of the plan with no `start` record in the log (e.g. a run that crashed
before logging it) falls back to the plan: start/stop = run.json `t0_unix` + plan `start_s`/`stop_s`
and the IPs of the plan's nodes; such windows carry `from_plan=True`. A `start` without `stop`
lasts until +inf (the end of the capture).
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass, field
from pathlib import Path

from uavcas.dataset.schema import FAMILIES
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
    stop_unix: float  # exclusive
    from_plan: bool = False


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


@dataclass(frozen=True)
class AttackLog:
    windows: tuple[AttackWindow, ...] = ()
    injections: tuple[Injection, ...] = field(default_factory=tuple)

    def of_family(self, *families: str) -> list[AttackWindow]:
        return [w for w in self.windows if w.family in families]


def _need(rec: dict, key: str, where: str):
    if key not in rec:
        raise LabelError(f"{where}: record has no '{key}'")
    return rec[key]


def read_attack_log(path: Path, plan: Plan | None = None, t0_unix: float | None = None) -> AttackLog:
    """Parse attacks.jsonl (may be absent for a benign run) and fill gaps from the plan."""
    starts: dict[str, dict] = {}
    stops: dict[str, float] = {}
    injections: list[Injection] = []
    if path.exists():
        for lineno, line in enumerate(path.read_text().splitlines(), 1):
            if not line.strip():
                continue
            where = f"{path}:{lineno}"
            try:
                rec = json.loads(line)
            except json.JSONDecodeError as exc:
                raise LabelError(f"{where}: not JSON ({exc.msg})") from None
            event = _need(rec, "event", where)
            try:
                if event == "start":
                    fam = _need(rec, "family", where)
                    if fam not in FAMILIES:
                        raise LabelError(f"{where}: unknown family {fam!r}")
                    starts[_need(rec, "attack_id", where)] = {**rec, "_where": where}
                elif event == "stop":
                    stops[_need(rec, "attack_id", where)] = float(_need(rec, "t_unix", where))
                elif event == "inject":
                    seq = rec.get("seq")
                    injections.append(
                        Injection(
                            attack_id=str(_need(rec, "attack_id", where)),
                            t_unix=float(_need(rec, "t_unix", where)),
                            src_ip=str(_need(rec, "src_ip", where)),
                            dst_ip=str(_need(rec, "dst_ip", where)),
                            protocol=int(_need(rec, "protocol", where)),
                            ip_id=int(_need(rec, "ip_id", where)),
                            ttl=int(_need(rec, "ttl", where)),
                            seq=None if seq is None else int(seq),
                        )
                    )
            except (TypeError, ValueError) as exc:
                if isinstance(exc, LabelError):
                    raise
                raise LabelError(f"{where}: bad field value ({exc})") from None
    windows: list[AttackWindow] = []
    for aid, rec in starts.items():
        attackers = tuple(rec.get("attacker_ips") or _plan_ips(plan, rec.get("attackers", [])))
        victims = tuple(rec.get("victim_ips") or _plan_ips(plan, rec.get("victims", [])))
        windows.append(
            AttackWindow(
                attack_id=aid,
                family=rec["family"],
                attacker_ips=attackers,
                victim_ips=victims,
                start_unix=float(_need(rec, "t_unix", rec["_where"])),
                stop_unix=stops.get(aid, math.inf),
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
