"""A root test's audit verdict, with what the host did told apart from what the emulation did.

A run's delay checks (per-hop delay error p90 and p99) fail when the delay stage releases
frames late. The stage runs at SCHED_FIFO, so when it is late by more than a check allows, the
vCPU itself was held up (another tenant, an interrupt storm): the host's contention, issue 41's
subject, not an error of the twin. The stage records its own lateness per frame (run.json
`delay_daemon.lag_hist_us`, upper bucket edges in microseconds). A failed delay check is the
host's when at least the check's share of frames (10 % for p90, 1 % for p99) left the stage later
than the check's limit, counted from the lower edge of each bucket (so the stage's own record
proves it). Such a run is an expected failure with the figures; any other failure (another
check, or a delay check the stage's lag does not explain) fails the test.

Stop 38 measured why: on this host the same runs failed their p99 check on the last landed
commit as on this one, with the same tail in the stage's lag histogram (docs/measurements.md).
"""

from __future__ import annotations

import json

import pytest

from uavcas.fidelity import read_fidelity
from uavcas.rundir import RunDir

SHARE = {"delay_error_p90_ms": 0.10, "delay_error_p99_ms": 0.01}  # the share of frames each check lets through


def late_share(lag_hist_us: dict[str, int], limit_ms: float) -> float:
    """The share of the stage's frames released more than `limit_ms` late, counting only the
    buckets whose lower edge is at or above the limit (a lower bound of the true share)."""
    edges = sorted((float(k), n) for k, n in lag_hist_us.items())
    total = sum(n for _, n in edges)
    late, lower = 0, 0.0
    for upper, n in edges:
        if lower >= limit_ms * 1000:
            late += n
        lower = upper
    return late / total if total else 0.0


def host_explained(rd: RunDir) -> list[str]:
    """The run's failed checks that the delay stage's own lateness explains."""
    fid = read_fidelity(rd.root)
    hist = json.loads(rd.run_json.read_text()).get("delay_daemon", {}).get("lag_hist_us") or {}
    return [c.name for c in fid.checks if not c.ok and c.name in SHARE and hist
            and late_share(hist, c.limit) >= SHARE[c.name]]


def assert_audit_passes(rd: RunDir) -> None:
    """The run's audit passed, or every check it failed is a delay check the host explains (xfail)."""
    info = rd.read_info()
    assert info.fidelity is not None, "the run was not audited"
    if info.fidelity.verdict == "pass":
        return
    explained = host_explained(rd)
    if info.fidelity.verdict == "fail" and explained and set(info.fidelity.failed) <= set(explained):
        pytest.xfail(f"the host held the delay stage up ({', '.join(explained)}: "
                     f"p90/p99 {info.fidelity.delay_error_p90_ms}/{info.fidelity.delay_error_p99_ms} ms); issue 41")
    raise AssertionError(f"audit failed, not explained by the delay stage's lateness: {info.fidelity}")
