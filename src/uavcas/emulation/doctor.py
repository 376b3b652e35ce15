"""`uavcas doctor`: what this machine offers, and a short measurement proving the shaper works.

The measurement builds a 3-node line (uav0 - uav1 - uav2) under its own prefix, shapes both hops
and checks end to end: TCP goodput, one-way delay, loss (tolerances in `selftest`). A figure
outside tolerance is measured once more before it counts as a failure, because other work on
the same cores can disturb a single short run.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from . import selftest
from .emulation import Emulation
from .naming import new_prefix
from .probe import Features, probe
from .selftest import Check, HopConfig

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
    checks: list[Check] = field(default_factory=list)
    retried: list[str] = field(default_factory=list)
    error: str | None = None

    @property
    def ok(self) -> bool:
        return self.error is None and bool(self.checks) and all(c.ok for c in self.checks)


def _measure(emu: Emulation) -> list[Check]:
    emu.apply_window(0)
    goodput = selftest.measure_goodput(emu, "uav0", "uav2")
    emu.apply_window(1)
    udp = selftest.measure_udp(emu, "uav0", "uav2", UDP_PROBES, UDP_PPS)
    return [selftest.goodput_check(goodput, min(h.rate_mbps for h in RATE_HOPS)),
            selftest.delay_check(udp["delays_ms"].get("median", float("nan")), IMPAIR_HOPS),
            selftest.loss_check(udp["loss"], UDP_PROBES, IMPAIR_HOPS)]


def run_doctor(prefix: str | None = None, measure: bool = True) -> DoctorResult:
    feats = probe()
    res = DoctorResult(feats)
    if not measure:
        return res
    try:
        with Emulation(two_hop_plan([RATE_HOPS, IMPAIR_HOPS]), prefix=prefix or new_prefix(), features=feats) as emu:
            checks = _measure(emu)
            if not all(c.ok for c in checks):
                res.retried = [c.name for c in checks if not c.ok]
                again = {c.name: c for c in _measure(emu)}
                checks = [c if c.ok else again[c.name] for c in checks]
            res.checks = checks
    except Exception as e:  # reported as one line by the CLI
        res.error = f"{type(e).__name__}: {e}"
    return res
