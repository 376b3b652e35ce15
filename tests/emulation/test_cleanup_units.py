"""`uavcas clean`'s process handling without root: processes that exit while they are looked at."""

from __future__ import annotations

import subprocess
import sys
import time

from uavcas.emulation import cleanup


def test_exists_for_a_live_a_zombie_and_a_reaped_process():
    p = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(30)"])
    try:
        assert cleanup._exists(p.pid)
    finally:
        p.kill()
    for _ in range(100):  # killed, not yet reaped: a zombie counts as gone
        if not cleanup._exists(p.pid):
            break
        time.sleep(0.01)
    assert not cleanup._exists(p.pid)
    p.wait()
    assert not cleanup._exists(p.pid)  # reaped: /proc/PID is gone


def test_a_process_exiting_between_open_and_read_counts_as_gone(monkeypatch):
    """The failure seen in one of five SIGKILL clean-ups: /proc/PID/stat opened, then the read
    fails with ESRCH because the process exited in between."""

    class Vanishing:
        def __enter__(self):
            return self

        def __exit__(self, *exc):
            return False

        def read(self):
            raise ProcessLookupError(3, "No such process")

    monkeypatch.setattr(cleanup, "open", lambda *a, **k: Vanishing(), raising=False)
    assert cleanup._exists(12345) is False


def test_kill_pids_tolerates_processes_that_already_exited():
    # exited but not reaped (zombies): their PIDs cannot be reused by someone else meanwhile
    gone = [subprocess.Popen([sys.executable, "-c", "pass"]) for _ in range(5)]
    live = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(30)"])
    deadline = time.monotonic() + 10
    while any(cleanup._exists(p.pid) for p in gone) and time.monotonic() < deadline:
        time.sleep(0.01)
    cleanup.kill_pids([p.pid for p in gone] + [live.pid], grace_s=0.5)
    assert live.wait(5) is not None
    assert [p.wait(5) for p in gone] == [0] * 5
