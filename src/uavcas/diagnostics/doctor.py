"""`uavcas doctor`: what this machine offers, and a short measurement proving the shaper works.

The measurement builds a 3-node line (uav0 - uav1 - uav2) under its own prefix, shapes both hops
and checks end to end: TCP goodput, one-way delay (median, p90, p99), loss (tolerances in
`selftest`). Meanwhile a `ContentionProbe` measures how contended the CPUs are: "contended" is a
warning (timing figures of runs made now are less faithful), "saturated" fails the doctor
whatever the figures say, because a short measurement can be lucky where a long run will not
be. A figure outside tolerance is measured once more before it counts as a failure.
"""

from __future__ import annotations

import argparse
import json
from dataclasses import dataclass, field
from pathlib import Path

from uavcas.atomic import atomic_write_text
from uavcas.emulation.emulation import Emulation
from uavcas.emulation.probe import Features, probe
from uavcas.network.naming import new_prefix
from uavcas.twin import model as m

from . import selftest
from .checks import Check, DelayTolerance, HopConfig, delay_checks, goodput_check, loss_check
from .contention import Contention, ContentionProbe


@dataclass(frozen=True)
class DoctorProfile:
    """What the self-test offers and how strictly it judges."""

    name: str
    rate_hops: list[HopConfig]  # window 0: TCP goodput
    impair_hops: list[HopConfig]  # window 1: UDP probes (delay, loss)
    udp_probes: int
    udp_pps: float
    tol: DelayTolerance
    contention_fails: bool  # a saturated machine fails the doctor
    startup_s: float = 10.0  # how long a measurement endpoint may take to start


# This machine: 20 Mbit/s bulk TCP, 1,500 probes/s of 200 B (2.4 Mbit/s, light next to 20).
NATIVE = DoctorProfile("native", [HopConfig(20.0, 1.0, 0.0)] * 2,
                       [HopConfig(20.0, 3.0, 0.02), HopConfig(20.0, 4.0, 0.03)], 3000, 1500.0, DelayTolerance(), True)
# A guest on an emulated CPU (QEMU TCG): every packet costs it tens of microseconds, so a tenth
# of the traffic; its timers fire late whenever the host preempts a vCPU thread (measured in the
# guest: wake-ups 0.3-0.5 ms late at p50, 10-46 ms at p99; netem's median delay 0.3-0.8 ms high
# per hop, its p90 up to 3 ms), so the median gets 1 ms per hop, the tail is only reported, and
# contention in the guest is not judged (an emulated CPU always looks contended; the host's is).
EMULATED_CPU = DoctorProfile("emulated-cpu", [HopConfig(2.0, 1.0, 0.0)] * 2,
                             [HopConfig(2.0, 3.0, 0.02), HopConfig(2.0, 4.0, 0.03)], 1500, 150.0,
                             DelayTolerance(median_ms=1.0, p90_ms=None, p99_ms=None), False, startup_s=120.0)
PROFILES = {p.name: p for p in (NATIVE, EMULATED_CPU)}


def two_hop_plan(windows: list[list[HopConfig]]):
    nodes = [m.Node(name=f"uav{i}", kind="uav", index=i, ip=f"10.78.0.{i + 1}", mac=f"02:00:00:78:00:{i:02x}")
             for i in range(3)]
    wins = []
    for w, hops in enumerate(windows):
        links = [m.Link(a=f"uav{k}", b=f"uav{k + 1}", kind="air", distance_m=100.0, pathloss_db=None, snr_db=None,
                        mcs=None, rate_mbps=h.rate_mbps, delay_ms=h.delay_ms, loss=h.loss) for k, h in enumerate(hops)]
        route = m.Route(src="uav0", dst="uav2", hops=["uav0", "uav1", "uav2"])
        wins.append(m.Window(index=w, t_s=5.0 * w, duration_s=5.0, positions={}, links=links, routes=[route]))
    return m.Plan(config="doctor", seed=0, window_s=5.0, profile="doctor", area_m=(1.0, 1.0, 0.0, 1.0),
                  nodes=nodes, windows=wins, attacks=[])


@dataclass
class DoctorResult:
    features: Features
    backend: str | None = None
    checks: list[Check] = field(default_factory=list)
    retried: list[str] = field(default_factory=list)
    contention: Contention | None = None
    error: str | None = None
    judge_contention: bool = True  # False: contention is reported, never failed on

    @property
    def saturated(self) -> bool:
        return self.judge_contention and self.contention is not None and self.contention.level == "saturated"

    @property
    def warnings(self) -> list[str]:
        if self.contention is None or self.contention.level == "quiet":
            return []
        note = "" if self.judge_contention else " (not judged: an emulated CPU)"
        return [f"machine {self.contention.level}{note}: {'; '.join(self.contention.reasons)}"]

    @property
    def ok(self) -> bool:
        return (self.error is None and bool(self.checks) and all(c.ok for c in self.checks)
                and not self.saturated)

    def to_dict(self, measured: bool = True) -> dict:
        return {"features": self.features.to_dict(), "backend": self.backend,
                "judge_contention": self.judge_contention,
                "ok": self.ok if measured else None, "error": self.error,
                "checks": [c.to_dict() for c in self.checks], "retried": list(self.retried),
                "contention": self.contention.to_dict() if self.contention else None,
                "warnings": self.warnings}

    @classmethod
    def from_dict(cls, d: dict) -> "DoctorResult":
        """Back from `to_dict` (e.g. the result a guest kernel wrote, `uavcas doctor --vm`)."""
        feats = Features(**{k: v for k, v in d["features"].items() if k != "shaper"})
        checks = [Check(**{k: v for k, v in c.items() if k != "ok"}) for c in d["checks"]]
        cont = d.get("contention")
        cont = Contention(**{k: v for k, v in cont.items() if k not in ("level", "reasons")}) if cont else None
        return cls(feats, d.get("backend"), checks, list(d.get("retried", [])), cont, d.get("error"),
                   d.get("judge_contention", True))


def _measure(emu: Emulation, prof: DoctorProfile) -> list[Check]:
    emu.apply_window(0)
    goodput = selftest.measure_goodput(emu, "uav0", "uav2", startup_s=prof.startup_s)
    emu.apply_window(1)
    udp = selftest.measure_udp(emu, "uav0", "uav2", prof.udp_probes, prof.udp_pps, startup_s=prof.startup_s)
    return [goodput_check(goodput, min(h.rate_mbps for h in prof.rate_hops)),
            *delay_checks(udp["delays_ms"], prof.impair_hops, prof.tol),
            loss_check(udp["loss"], prof.udp_probes, prof.impair_hops)]


def run_doctor(prefix: str | None = None, measure: bool = True, backend: str | None = None,
               profile: DoctorProfile = NATIVE) -> DoctorResult:
    feats = probe()
    res = DoctorResult(feats, backend or feats.shaper, judge_contention=profile.contention_fails)
    if not measure:
        return res
    load = ContentionProbe()
    try:
        with load:
            plan = two_hop_plan([profile.rate_hops, profile.impair_hops])
            with Emulation(plan, prefix=prefix or new_prefix(), features=feats, backend=backend) as emu:
                checks = _measure(emu, profile)
                if not all(c.ok for c in checks):
                    res.retried = [c.name for c in checks if not c.ok]
                    again = {c.name: c for c in _measure(emu, profile)}
                    checks = [c if c.ok else again[c.name] for c in checks]
                res.checks = checks
    except Exception as e:  # reported as one line by the CLI
        res.error = f"{type(e).__name__}: {e}"
    res.contention = load.result
    return res


def main(argv: list[str] | None = None) -> None:
    """`python -m uavcas.diagnostics.doctor --json FILE`: the measurement alone, as JSON (what the
    VM guest runs: the CLI would import every sub-command on a slow emulated CPU)."""
    ap = argparse.ArgumentParser(description=main.__doc__.splitlines()[0])
    ap.add_argument("--json", type=Path, required=True)
    ap.add_argument("--profile", choices=sorted(PROFILES), default=NATIVE.name)
    a = ap.parse_args(argv)
    res = run_doctor(profile=PROFILES[a.profile])
    atomic_write_text(a.json, json.dumps(res.to_dict(), indent=1) + "\n")
    raise SystemExit(0 if res.ok else 1)


if __name__ == "__main__":
    main()
