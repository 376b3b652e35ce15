"""A `Contention` measurement of a quiet 2-core machine, with any figure overridden (the doctor's
and the contention levels' unit tests judge the same record)."""

from __future__ import annotations

from uavcas.diagnostics.contention import Contention


def quiet(**kw) -> Contention:
    base = dict(seconds=10.0, cpus=2, psi_some_pct=2.0, runq_per_cpu=0.3, steal_pct=0.0, timer_late_p50_us=80.0,
                timer_late_p99_us=200.0, timer_wakeups=4000)
    return Contention(**{**base, **kw})
