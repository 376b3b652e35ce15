"""The self-test's checks without root: per-hop delay tolerances, the binomial loss interval, the
kernel's receive timestamp."""

from __future__ import annotations

import socket
import struct

import pytest

from uavcas.diagnostics.checks import DelayTolerance, HopConfig, binomial_interval, delay_checks, loss_check
from uavcas.diagnostics.doctor import EMULATED_CPU
from uavcas.diagnostics.selftest import kernel_rx_ns

HOPS = [HopConfig(20, 3.0, 0.0), HopConfig(20, 4.0, 0.0)]


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


def test_loss_tolerance_is_binomial_99():
    lo, hi = binomial_interval(3000, 0.0494)
    assert lo < 0.0494 < hi and hi - lo < 0.025
    hops = [HopConfig(10, 1, 0.02), HopConfig(10, 1, 0.03)]
    c = loss_check(0.05, 3000, hops)
    assert c.expected == pytest.approx(4.94) and c.ok
    wide = loss_check(0.05, 3000, hops, confidence=0.9999)
    assert wide.low < c.low < c.high < wide.high and not loss_check(0.07, 3000, hops, 0.9999).ok


def test_kernel_receive_timestamp_is_read_from_the_ancillary_data():
    anc = [(socket.SOL_SOCKET, 35, struct.pack("@qq", 1_700_000_000, 123))]
    assert kernel_rx_ns(anc) == 1_700_000_000 * 10**9 + 123
    assert kernel_rx_ns([]) > 1_700_000_000 * 10**9  # none attached: now
