"""The doctor's verdict logic, without root: checks, delay tolerances, contention levels, JSON."""

from __future__ import annotations

import json
import socket
import struct

import numpy as np

from uavcas.emulation import contention
from uavcas.emulation.contention import Contention
from uavcas.emulation.doctor import EMULATED_CPU, DoctorResult
from uavcas.emulation.probe import Features
from uavcas.emulation.selftest import Check, DelayTolerance, HopConfig, delay_checks, kernel_rx_ns, loss_check

HOPS = [HopConfig(20, 3.0, 0.0), HopConfig(20, 4.0, 0.0)]
FEATS = Features(root=True, netns=True, netem=False, htb=True, tbf=True, nft=True, nft_bridge_numgen=True,
                 nfqueue=True, br_netfilter=True, cgroup=None)


def quiet(**kw) -> Contention:
    base = dict(seconds=10.0, cpus=2, psi_some_pct=2.0, runq_per_cpu=0.3, steal_pct=0.0, timer_late_p50_us=80.0,
                timer_late_p99_us=200.0, timer_wakeups=4000)
    return Contention(**{**base, **kw})


def test_delay_checks_scale_per_hop_and_bound_the_tail():
    tol = DelayTolerance(median_ms=0.25, p90_ms=0.5, p99_ms=1.0)
    good = {"median": 7.1, "p90": 7.3, "p99": 8.5}
    assert all(c.ok for c in delay_checks(good, HOPS, tol))
    p50, p90, p99 = delay_checks({"median": 7.1, "p90": 8.2, "p99": 9.5}, HOPS, tol)
    assert p50.ok and not p90.ok and not p99.ok  # the median alone passes a stage with a bad tail
    assert (p90.high, p99.high) == (8.0, 9.0) and p50.low == 6.5
    assert not delay_checks({"median": 6.4, "p90": 7.0, "p99": 7.1}, HOPS, tol)[0].ok  # early is wrong too
    assert not any(c.ok for c in delay_checks({}, HOPS, tol))  # no probe arrived: nothing passes
    only_median = delay_checks({"median": 8.9, "p90": 30.0, "p99": 60.0}, HOPS, EMULATED_CPU.tol)
    assert [c.name for c in only_median] == ["one-way delay p50"] and only_median[0].ok  # TCG: tail not judged


def test_check_is_plain_json_booleans_and_floats():
    c = loss_check(0.05, 3000, [HopConfig(10, 1, 0.02), HopConfig(10, 1, 0.03)])  # bounds come from scipy
    assert type(c.ok) is bool and type(c.low) is float
    text = json.dumps(c.to_dict())
    assert '"ok": true' in text
    res = DoctorResult(FEATS, "htb-nft-nfqueue", [c, Check("x", "ms", 1, 1, np.float64(5.0), 0, 2)],
                       contention=quiet())
    d = json.loads(json.dumps(res.to_dict()))
    assert d["ok"] is False and [x["ok"] for x in d["checks"]] == [True, False]
    assert d["contention"]["level"] == "quiet" and d["warnings"] == []


def test_contention_levels():
    assert quiet().level == "quiet" and quiet().reasons == []
    busy = quiet(psi_some_pct=contention.CONTENDED_PSI_SOME_PCT + 5)
    assert busy.level == "contended" and "CPU pressure" in busy.reasons[0]
    assert quiet(timer_late_p99_us=contention.CONTENDED_TIMER_P99_US + 1).level == "contended"
    assert quiet(steal_pct=contention.CONTENDED_STEAL_PCT + 1).level == "contended"
    assert quiet(timer_late_p99_us=contention.SATURATED_TIMER_P99_US + 1).level == "saturated"
    assert quiet(runq_per_cpu=contention.SATURATED_RUNQ_PER_CPU + 0.1).level == "saturated"
    assert quiet(psi_some_pct=contention.SATURATED_PSI_SOME_PCT + 1).level == "saturated"
    assert quiet(psi_some_pct=None).level == "quiet"  # kernels without PSI


def test_saturated_machine_fails_the_doctor_even_when_every_figure_passes():
    ok = Check("x", "ms", 1, 1, 1.0, 0, 2)
    assert DoctorResult(FEATS, "b", [ok], contention=quiet()).ok
    sat = DoctorResult(FEATS, "b", [ok], contention=quiet(runq_per_cpu=3.0))
    assert sat.saturated and not sat.ok and sat.warnings and "saturated" in sat.warnings[0]
    contended = DoctorResult(FEATS, "b", [ok], contention=quiet(psi_some_pct=60.0))
    assert contended.ok and "contended" in contended.warnings[0]


def test_kernel_receive_timestamp_is_read_from_the_ancillary_data():
    anc = [(socket.SOL_SOCKET, 35, struct.pack("@qq", 1_700_000_000, 123))]
    assert kernel_rx_ns(anc) == 1_700_000_000 * 10**9 + 123
    assert kernel_rx_ns([]) > 1_700_000_000 * 10**9  # none attached: now


def test_contention_probe_measures_this_machine():
    c = contention.measure(0.3)
    assert c is not None and c.cpus >= 1 and c.timer_wakeups > 20 and c.seconds >= 0.3
    assert c.level in ("quiet", "contended", "saturated")
