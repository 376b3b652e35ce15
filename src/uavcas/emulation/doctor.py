"""`uavcas doctor`: what this machine offers, and a short measurement proving the shaper works.

The measurement builds a 3-node line (uav0 - uav1 - uav2) under its own prefix, shapes both hops
and checks end to end: TCP goodput, one-way delay (median, p90, p99), loss (tolerances in
`selftest`). Meanwhile a `ContentionProbe` measures how contended the CPUs are: "contended" is a
warning (timing figures of runs made now are less faithful), "saturated" fails the doctor
whatever the figures say, because a short measurement can be lucky where a long run will not
be. A figure outside tolerance is measured once more before it counts as a failure.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from . import selftest
from .contention import Contention, ContentionProbe
from .emulation import Emulation
from .naming import new_prefix
from .probe import Features, probe
from .selftest import Check, DelayTolerance, HopConfig

RATE_HOPS = [HopConfig(20.0, 1.0, 0.0), HopConfig(20.0, 1.0, 0.0)]
IMPAIR_HOPS = [HopConfig(20.0, 3.0, 0.02), HopConfig(20.0, 4.0, 0.03)]
UDP_PROBES = 3000
UDP_PPS = 1500


def two_hop_plan(windows: list[list[HopConfig]]):
    from uavcas.twin import model as m

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

    @property
    def saturated(self) -> bool:
        return self.contention is not None and self.contention.level == "saturated"

    @property
    def warnings(self) -> list[str]:
        if self.contention is None or self.contention.level == "quiet":
            return []
        return [f"machine {self.contention.level}: {'; '.join(self.contention.reasons)}"]

    @property
    def ok(self) -> bool:
        return (self.error is None and bool(self.checks) and all(c.ok for c in self.checks)
                and not self.saturated)

    def to_dict(self, measured: bool = True) -> dict:
        return {"features": self.features.to_dict(), "backend": self.backend,
                "ok": self.ok if measured else None, "error": self.error,
                "checks": [c.to_dict() for c in self.checks], "retried": list(self.retried),
                "contention": self.contention.to_dict() if self.contention else None,
                "warnings": self.warnings}


def _measure(emu: Emulation, tol: DelayTolerance) -> list[Check]:
    emu.apply_window(0)
    goodput = selftest.measure_goodput(emu, "uav0", "uav2")
    emu.apply_window(1)
    udp = selftest.measure_udp(emu, "uav0", "uav2", UDP_PROBES, UDP_PPS)
    return [selftest.goodput_check(goodput, min(h.rate_mbps for h in RATE_HOPS)),
            *selftest.delay_checks(udp["delays_ms"], IMPAIR_HOPS, tol),
            selftest.loss_check(udp["loss"], UDP_PROBES, IMPAIR_HOPS)]


def run_doctor(prefix: str | None = None, measure: bool = True, backend: str | None = None,
               tol: DelayTolerance = DelayTolerance()) -> DoctorResult:
    feats = probe()
    res = DoctorResult(feats, backend or feats.shaper)
    if not measure:
        return res
    load = ContentionProbe()
    try:
        with load:
            with Emulation(two_hop_plan([RATE_HOPS, IMPAIR_HOPS]), prefix=prefix or new_prefix(), features=feats,
                           backend=backend) as emu:
                checks = _measure(emu, tol)
                if not all(c.ok for c in checks):
                    res.retried = [c.name for c in checks if not c.ok]
                    again = {c.name: c for c in _measure(emu, tol)}
                    checks = [c if c.ok else again[c.name] for c in checks]
                res.checks = checks
    except Exception as e:  # reported as one line by the CLI
        res.error = f"{type(e).__name__}: {e}"
    res.contention = load.result
    return res
