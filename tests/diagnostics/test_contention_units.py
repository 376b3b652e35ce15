"""Contention levels from their documented thresholds, and the probe on this machine."""

from __future__ import annotations

from helpers.contention import quiet
from uavcas.diagnostics import contention


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


def test_contention_probe_measures_this_machine():
    c = contention.measure(0.3)
    assert c is not None and c.cpus >= 1 and c.timer_wakeups > 20 and c.seconds >= 0.3
    assert c.level in ("quiet", "contended", "saturated")
