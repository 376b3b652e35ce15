"""Registry of live runs and `uavcas clean`: remove exactly what a crashed run left.

Before a run creates anything it writes `/run/uavcas/<prefix>/run.json` (every namespace and
cgroup it *will* create) and holds an exclusive `flock` on `/run/uavcas/<prefix>/lock` for its
whole life. The kernel drops the lock when the process dies, even by SIGKILL, so `clean` can
tell a crashed run (lock free) from a live one (lock held; skipped unless forced).

All iptables/nft rules, qdiscs, bridges and veths of a run live inside its own namespaces, so
deleting those namespaces removes them; processes keep a namespace alive, so they are killed
first, by PID, from `ip netns pids`. Nothing outside the registry (or, with an explicit prefix
and no registry, outside `<prefix>-*` namespaces next to a `<prefix>-fab`) is touched.
"""

from __future__ import annotations

import fcntl
import json
import os
import shutil
import signal
import time
from dataclasses import asdict, dataclass, field
from pathlib import Path

from uavcas.network.naming import RUN_ROOT, Naming, check_prefix

from . import kernel


@dataclass
class RunRecord:
    prefix: str
    pid: int
    namespaces: list[str]
    cgroups: list[str] = field(default_factory=list)  # directories, deepest first
    created_unix: float = field(default_factory=time.time)


class RunLock:
    """Holds the run's registry entry and lock; `release()` removes both."""

    def __init__(self, record: RunRecord) -> None:
        self.record = record
        self.dir = Naming(record.prefix).run_dir
        self.dir.mkdir(parents=True, exist_ok=True)
        self._fd = os.open(self.dir / "lock", os.O_RDWR | os.O_CREAT | os.O_CLOEXEC, 0o600)
        try:
            fcntl.flock(self._fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            os.close(self._fd)
            raise RuntimeError(f"prefix {record.prefix!r} is in use by a live run") from None
        self.save()

    def save(self) -> None:
        tmp = self.dir / ".run.json.tmp"
        tmp.write_text(json.dumps(asdict(self.record), indent=1))
        os.replace(tmp, self.dir / "run.json")

    def release(self) -> None:
        shutil.rmtree(self.dir, ignore_errors=True)
        os.close(self._fd)


def is_live(prefix: str) -> bool:
    lock = Naming(prefix).run_dir / "lock"
    try:
        fd = os.open(lock, os.O_RDWR | os.O_CLOEXEC)
    except FileNotFoundError:
        return False
    try:
        fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        fcntl.flock(fd, fcntl.LOCK_UN)
        return False
    except BlockingIOError:
        return True
    finally:
        os.close(fd)


def registered_prefixes() -> list[str]:
    if not RUN_ROOT.is_dir():
        return []
    return sorted(p.name for p in RUN_ROOT.iterdir() if (p / "run.json").exists() or (p / "lock").exists())


def _record(prefix: str) -> RunRecord | None:
    try:
        return RunRecord(**json.loads((Naming(prefix).run_dir / "run.json").read_text()))
    except (FileNotFoundError, ValueError, TypeError):
        return None


@dataclass
class CleanReport:
    prefix: str
    skipped_live: bool = False
    killed_pids: list[int] = field(default_factory=list)
    namespaces: list[str] = field(default_factory=list)
    cgroups: list[str] = field(default_factory=list)
    error: str | None = None  # one line: what could not be removed (the other prefixes still are)


def kill_pids(pids: list[int], grace_s: float = 1.0) -> list[int]:
    """SIGTERM, then SIGKILL what is left after `grace_s`. Only the given PIDs."""
    alive = []
    for pid in pids:
        try:
            os.kill(pid, signal.SIGTERM)
            alive.append(pid)
        except ProcessLookupError:
            pass
    deadline = time.monotonic() + grace_s
    while alive and time.monotonic() < deadline:
        time.sleep(0.02)
        alive = [p for p in alive if _exists(p)]
    for pid in alive:
        try:
            os.kill(pid, signal.SIGKILL)
        except ProcessLookupError:
            pass
    return pids


def _exists(pid: int) -> bool:
    """Alive and not a zombie. A process may exit at any point of this: /proc/PID vanishes
    (FileNotFoundError), or the read after a successful open fails with ESRCH
    (ProcessLookupError); both mean it is gone."""
    try:
        with open(f"/proc/{pid}/stat") as fh:
            return fh.read().rsplit(")", 1)[1].split()[0] != "Z"
    except (OSError, IndexError):
        return False


def remove_namespaces(namespaces: list[str]) -> list[str]:
    present = set(kernel.netns_list())
    mine = [ns for ns in namespaces if ns in present]
    pids = sorted({pid for ns in mine for pid in kernel.netns_pids(ns) if pid != os.getpid()})
    kill_pids(pids)
    if mine:
        try:
            kernel.run_batch("ip", None, [f"netns del {ns}" for ns in mine])
        except kernel.KernelError:
            # one batch stops at its first failure (e.g. a namespace someone else removed
            # meanwhile): delete what is still there one by one, failing only on a real error
            for ns in sorted(set(mine) & set(kernel.netns_list())):
                kernel.run(["ip", "netns", "del", ns])
    return mine


def remove_cgroups(dirs: list[str]) -> list[str]:
    removed = []
    for d in dirs:  # deepest first; a cgroup dir is removed with rmdir, never rm -r
        path = Path(d)
        if not path.is_dir():
            continue
        try:
            pids = [int(x) for x in (path / "cgroup.procs").read_text().split()]
        except OSError:  # removed meanwhile, or no procs file
            pids = []
        kill_pids(pids, grace_s=0.5)
        for _ in range(50):
            try:
                path.rmdir()
                removed.append(d)
                break
            except OSError:
                time.sleep(0.02)
    return removed


def clean(prefix: str | None = None, force: bool = False) -> list[CleanReport]:
    """Clean one prefix, or every registered run that is not live. Returns what was removed."""
    prefixes = [check_prefix(prefix)] if prefix else registered_prefixes()
    reports = []
    for p in prefixes:
        rep = CleanReport(p)
        reports.append(rep)
        if is_live(p) and not force:
            rep.skipped_live = True
            continue
        try:
            _clean_one(rep)
        except (OSError, kernel.KernelError) as e:
            rep.error = f"{type(e).__name__}: {str(e).splitlines()[0] if str(e) else ''}"
    return reports


def reclaim_dead() -> list[CleanReport]:
    """Clean every registered run whose owner is dead: its run.json's PID gone and its lock free.

    What a run killed with no teardown at all (SIGKILL) left; a campaign's next run on the host
    calls this first. A run being set up (no run.json yet: written only once the lock is held) or
    still alive is never touched, so concurrent runs on one host are safe.
    """
    reports = []
    for p in registered_prefixes():
        rec = _record(p)
        if rec is None or _exists(rec.pid) or is_live(p):
            continue
        reports.extend(clean(p))
    return reports


def _clean_one(rep: CleanReport) -> None:
    rec = _record(rep.prefix)
    naming = Naming(rep.prefix)
    if rec is not None:
        namespaces, cgroups = rec.namespaces, rec.cgroups
    else:
        # No registry: only the shape a uavcas run has (a fabric namespace) identifies it.
        all_ns = kernel.netns_list()
        namespaces = [ns for ns in all_ns if naming.owns_ns(ns)] if naming.fabric_ns in all_ns else []
        cgroups = []
    present = set(kernel.netns_list())
    rep.killed_pids = [pid for ns in namespaces if ns in present for pid in kernel.netns_pids(ns)]
    rep.namespaces = remove_namespaces(namespaces)
    rep.cgroups = remove_cgroups(cgroups)
    shutil.rmtree(naming.run_dir, ignore_errors=True)
