"""Real-time tiers: the control plane's urgent() and the machine-wide softirq boost with holders."""

from __future__ import annotations

import os
import subprocess

import pytest

from uavcas.emulation import cleanup, priority
from uavcas.network.naming import new_prefix

pytestmark = pytest.mark.root


def _policy(pid: int = 0) -> int:
    return os.sched_getscheduler(pid) & ~os.SCHED_RESET_ON_FORK


def test_urgent_lifts_the_block_and_what_it_starts_only_if_asked():
    assert _policy() == os.SCHED_OTHER
    with priority.urgent(3) as mode:
        assert mode == "fifo" and _policy() == os.SCHED_FIFO and os.sched_getparam(0).sched_priority == 3
        inherited = subprocess.run(["sh", "-c", "chrt -p $$"], capture_output=True, text=True).stdout
    with priority.urgent(3, inherit=False):
        reset = subprocess.run(["sh", "-c", "chrt -p $$"], capture_output=True, text=True).stdout
    assert "SCHED_FIFO" in inherited and "SCHED_OTHER" in reset
    assert _policy() == os.SCHED_OTHER  # back to normal after the block
    with priority.urgent(0) as mode:
        assert mode == "normal" and _policy() == os.SCHED_OTHER


def test_the_last_live_holder_restores_the_softirq_threads(tmp_path, monkeypatch):
    monkeypatch.setattr(priority, "RUN_ROOT", tmp_path)
    before = priority.softirq_threads()
    if not before:
        pytest.skip("no ksoftirqd threads visible here")
    outer, inner = new_prefix(), new_prefix()
    lock = cleanup.RunLock(cleanup.RunRecord(outer, os.getpid(), []))  # the outer run is live
    try:
        with priority.softirq_boost(outer) as boosted:
            assert boosted
            with priority.softirq_boost(inner):
                assert all(p == os.SCHED_FIFO for p, _ in priority.softirq_threads().values())
            # the inner run left; the outer, live, still holds the boost
            assert all(p == os.SCHED_FIFO for p, _ in priority.softirq_threads().values())
            assert not priority.release_softirq()  # a clean-up finds a live holder: keeps it
    finally:
        lock.release()
    assert priority.softirq_threads() == before and not (tmp_path / priority.SOFTIRQ_STATE).exists()
    # a holder that died without leaving (SIGKILL) does not keep the boost for ever
    dead = new_prefix()
    with priority._state() as state:
        state.update({"original": {str(p): list(v) for p, v in before.items()}, "holders": [dead]})
    for pid in before:
        os.sched_setscheduler(pid, os.SCHED_FIFO, os.sched_param(priority.SOFTIRQ_RT_PRIORITY))
    assert priority.release_softirq() and priority.softirq_threads() == before
