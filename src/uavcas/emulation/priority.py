"""CPU priority for a run's time-critical work on a shared machine.

On two cores shared with the traffic, the captures, the attack tools and other people's jobs, a
window change at normal priority waited up to 1 s for CPU (100 UAVs: forwarding computed in
20 ms idle, 650-990 ms under load). Two tiers above everyone else, both SCHED_FIFO so that a
wake-up preempts CFS work at once:

* the delay stage (`nfqdelay`, `DELAY_RT_PRIORITY`): it must release packets on time;
* the control plane while it changes the network (`urgent()`: window changes, attack starts
  and stops), `CONTROL_RT_PRIORITY`, below the delay stage; it drops back to normal right
  after. Short-lived tools it starts meanwhile (the ip, tc, nft, bridge batches of a window
  change) inherit it with `inherit=True`; with `inherit=False` (attack actions, which start
  long-running tools such as hping3) children start at normal priority (SCHED_RESET_ON_FORK).

* the kernel's softirq threads (`softirq_boost()`, `SOFTIRQ_RT_PRIORITY`, between the two)
  for the length of a run. Packet processing that overflows an interrupt's budget is handed to
  ksoftirqd, a normal CFS thread: under a load of 20-40 runnable tasks, frames already stamped
  by the receiving port then waited 2-5 ms for it (100 UAVs: per-hop delay error p99 2.2-3.7
  ms; with the boost 0.23 ms). It is machine-wide: the original policies and the runs holding
  the boost are kept in `RUN_ROOT/softirq.json`; the last holder to finish restores them (a run
  killed with SIGKILL leaves the boost in place until another run ends, or until
  `release_softirq()` finds no live holder).

Real-time time is bounded by the kernel's RT throttling (sched_rt_runtime_us: 95 % of each
second), so a runaway cannot freeze the machine. Where SCHED_FIFO is refused (no CAP_SYS_NICE)
`urgent()` falls back to nice -15, and to nothing if that is refused too.
"""

from __future__ import annotations

import fcntl
import json
import os
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

from uavcas.atomic import atomic_write_text
from uavcas.network.naming import RUN_ROOT

from . import cleanup

DELAY_RT_PRIORITY = 10
SOFTIRQ_RT_PRIORITY = 9
CONTROL_RT_PRIORITY = 5
FALLBACK_NICE = -15
SOFTIRQ_STATE = "softirq.json"
SOFTIRQ_LOCK = "softirq.lock"


@contextmanager
def urgent(priority: int = CONTROL_RT_PRIORITY, inherit: bool = True) -> Iterator[str]:
    """Run the block at SCHED_FIFO `priority` (what it spawns too, if `inherit`); yields the mode."""
    if priority <= 0:
        yield "normal"
        return
    old_policy = os.sched_getscheduler(0)
    old_param = os.sched_getparam(0)
    old_nice = os.getpriority(os.PRIO_PROCESS, 0)
    reset = 0 if inherit else os.SCHED_RESET_ON_FORK
    mode = "normal"
    try:
        os.sched_setscheduler(0, os.SCHED_FIFO | reset, os.sched_param(priority))
        mode = "fifo"
    except OSError:
        try:
            if reset:
                os.sched_setscheduler(0, os.SCHED_OTHER | reset, os.sched_param(0))
            os.setpriority(os.PRIO_PROCESS, 0, FALLBACK_NICE)
            mode = "nice"
        except OSError:
            pass
    try:
        yield mode
    finally:
        if mode == "fifo":
            os.sched_setscheduler(0, old_policy, old_param)
        elif mode == "nice":
            os.setpriority(os.PRIO_PROCESS, 0, old_nice)


def softirq_threads() -> dict[int, tuple[int, int]]:
    """ksoftirqd threads: pid -> (policy, priority)."""
    out = {}
    for d in Path("/proc").iterdir():
        if not d.name.isdigit():
            continue
        try:
            if (d / "comm").read_text().startswith("ksoftirqd/"):
                pid = int(d.name)
                out[pid] = (os.sched_getscheduler(pid), os.sched_getparam(pid).sched_priority)
        except OSError:  # gone, or not ours to read
            continue
    return out


@contextmanager
def softirq_boost(prefix: str, priority: int = SOFTIRQ_RT_PRIORITY) -> Iterator[bool]:
    """Softirq threads at SCHED_FIFO `priority` while the block runs (see the module docstring).

    Yields whether the boost is in place. `RUN_ROOT/softirq.json` holds the threads' original
    policies and the prefixes of the runs holding the boost; the last holder to leave (holders
    whose run is no longer live are dropped) restores the originals.
    """
    if priority <= 0:
        yield False
        return
    boosted = False
    try:
        with _state() as state:
            if not state.get("original"):
                state["original"] = {str(p): list(v) for p, v in softirq_threads().items()}
            state["holders"] = sorted(set(state.get("holders", [])) | {prefix})
            for pid in state["original"]:
                os.sched_setscheduler(int(pid), os.SCHED_FIFO, os.sched_param(priority))
            boosted = bool(state["original"])
    except OSError:
        pass
    try:
        yield boosted
    finally:
        release_softirq(prefix)


def release_softirq(prefix: str | None = None) -> bool:
    """Leave the boost (as `prefix`); restore the original policies when no live run holds it.

    Returns whether they were restored. With `prefix` None only dead holders are dropped: what
    a clean-up after a killed run may call.
    """
    with _state() as state:
        if not state:
            return False
        holders = [h for h in state.get("holders", []) if h != prefix and cleanup.is_live(h)]
        state["holders"] = holders
        if holders:
            return False
        for pid, (policy, prio) in state.get("original", {}).items():
            try:
                os.sched_setscheduler(int(pid), policy, os.sched_param(prio))
            except OSError:
                continue
        state.clear()
        return True


@contextmanager
def _state() -> Iterator[dict]:
    """The boost's state file, read and written under an exclusive lock (runs end concurrently)."""
    RUN_ROOT.mkdir(parents=True, exist_ok=True)
    path = RUN_ROOT / SOFTIRQ_STATE
    with open(RUN_ROOT / SOFTIRQ_LOCK, "a") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)
        try:
            state = json.loads(path.read_text()) if path.exists() else {}
        except ValueError:
            state = {}
        yield state
        if state:
            atomic_write_text(path, json.dumps(state) + "\n")
        else:
            path.unlink(missing_ok=True)
