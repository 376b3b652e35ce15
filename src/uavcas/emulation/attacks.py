"""Execute a plan's attack schedule on a running Emulation and write the attack log.

The runner calls `prepare()` before t0, `start(attack)` / `halt(attack)` at the planned times,
`calibrate(attack)` at the family's calibration times and `finish_all()` after the schedule; what each does is the
family's own rule (`uavcas.attacks.<family>`). This class holds what the families share: the emulation, the
records of the attack log (`uavcas.events`), per-attack state, background processes and the
current window (re-applied when a family changes forwarding mid-window).

Times: a `start` record's t_unix is taken just *before* the action and a `stop` record's just
*after* it is fully undone, so every attack packet and effect lies inside [start, stop). A family
may return its own `t_unix` instead: a family whose effect is a rule in force (the blackhole's
drop table) the moment the rule was installed and the moment just before it was removed, so
[start, stop) is exactly when the rule held; a flood a later start (when its first packet could
go) and an earlier stop (when its last packet left), with `crossed_unix` on the stop record for
when that packet can have crossed the network: its packets are observed inside [start, crossed).

A stop has a time-critical half (the family's `halt`: the attack acts no more when it returns)
and a rest (waiting for tools, counters, clean-up, the `stop` record), run in a worker thread:
two attacks stopping at one instant, or a stop just before a window change, used to delay the
next event by the first stop's bookkeeping (56-200 ms in 21 of 64 medium-campaign runs). A
`start` waits for the unfinished stops that share one of its attackers (a flood's closed gate
stays in the attacker's namespace until its stop is finished).
"""

from __future__ import annotations

import signal
import threading
import time
from collections.abc import Callable
from concurrent.futures import Future, ThreadPoolExecutor
from pathlib import Path
from typing import TYPE_CHECKING, Any

from uavcas.attacks import family
from uavcas.events import AttackRecord, AttackStart, AttackStop, read_attack_records
from uavcas.network.forwarding import Detour

from .apps.procs import Proc

if TYPE_CHECKING:
    from uavcas.twin.model import Attack, Plan, Window


class AttackError(RuntimeError):
    """An attack could not be started or stopped; names the attack."""


class AttackExecutor:  # implements uavcas.attacks.AttackExecutor, the protocol the families type against
    def __init__(self, emu, plan: "Plan", work_dir: Path, duration_s: float,
                 on_event: Callable[[AttackRecord], None] | None = None) -> None:
        self.emu, self.plan = emu, plan
        self.work_dir, self.log_dir = work_dir, work_dir / "logs"
        self.duration_s = duration_s
        self.on_event = on_event or (lambda rec: None)
        self.records: list[AttackRecord] = []
        self.active: dict[str, "Attack"] = {}
        self.state: dict[str, Any] = {}  # family-owned, keyed by attack id (or attack id/attacker)
        self.processes: list[Proc] = []  # stopped at the end whatever happened
        self.event_logs: list[Path] = []  # JSONL logs attack processes write (read by collect())
        self.window: "Window | None" = None
        self.errors: list[str] = []
        self.inject_records: list[AttackRecord] = []
        # called with (window index, shapes) after every mid-window reshape (the runner's sampler)
        self.on_reshape: Callable[[int, list], None] = lambda window, shapes: None
        self._finishing: dict[str, tuple["Attack", Future]] = {}  # stops halted, not yet finished
        self._pool: ThreadPoolExecutor | None = None
        self._log_lock = threading.Lock()  # records and on_event from the finishing threads too

    # what the families use -----------------------------------------------------------------------
    def ip(self, node: str) -> str:
        return self.plan.node(node).ip

    def index(self, node: str) -> int:
        return self.plan.node(node).index

    def spec(self, a: "Attack"):
        return a.spec

    @staticmethod
    def now() -> float:
        return time.time()

    def log(self, rec: AttackRecord) -> AttackRecord:
        with self._log_lock:
            self.records.append(rec)
            self.on_event(rec)
        return rec

    def add_process(self, proc: Proc, event_log: Path | None = None) -> None:
        self.processes.append(proc)
        if event_log is not None:
            self.event_logs.append(event_log)

    def bs_of(self, uav: str) -> str:
        uavs = [n.name for n in self.plan.nodes if n.kind == "uav"]
        bss = [n.name for n in self.plan.nodes if n.kind == "bs"]
        return bss[uavs.index(uav) % len(bss)]

    def reapply_window(self) -> dict[str, Any]:
        """Re-apply the current window with the detours of the attacks active now (shaping is
        unchanged, so only the FDB and the detour table move)."""
        w = self.window
        if w is None:
            raise AttackError("no window applied yet")
        detours = self.wormholes_for(w)
        rep = self.emu.apply_links(w.links, [r.hops for r in w.routes], detours, window_index=w.index,
                                   overrides=self.shape_overrides_for(w))
        fwd = self.emu.forwarding
        paths = {d.key: fwd.detour_path(d.victim, d.bs) for d in detours} if fwd else {}
        return {"fdb_changes": rep.fdb_changes, "paths": paths, "rejected": list(rep.rejected)}

    def reshape(self) -> None:
        """Re-shape the current window's links with the overrides of the attacks active now
        (forwarding unchanged: `Emulation.reshape`); the sampler starts a new segment of the
        window's counters there (shaping.jsonl `segment`)."""
        w = self.window
        if w is None:
            raise AttackError("no window applied yet")
        self.on_reshape(w.index, self.emu.reshape(w.links, self.shape_overrides_for(w)))

    # lifecycle -----------------------------------------------------------------------------
    def prepare(self) -> None:
        """Before t0: e.g. start attack processes (idle until their attack starts)."""
        for a in self.plan.attacks:
            try:
                family(a.family).prepare(self, a)
            except Exception as e:
                raise AttackError(f"{a.attack_id}: prepare failed: {e}") from e

    def start(self, a: "Attack") -> AttackStart:
        for aid, (b, _) in list(self._finishing.items()):
            if set(b.attackers) & set(a.attackers):
                self._wait(aid)
        t = time.time()
        try:
            extra = family(a.family).start(self, a)
        except Exception as e:
            raise AttackError(f"{a.attack_id}: start failed: {e}") from e
        self.active[a.attack_id] = a
        t = extra.pop("t_unix", t)  # a family may know better when its first packet could go
        rec = AttackStart(attack_id=a.attack_id, family=a.family, attackers=list(a.attackers),
                          attacker_ips=[self.ip(x) for x in a.attackers], victims=list(a.victims),
                          victim_ips=[self.ip(v) for v in a.victims], t_unix=t, params=dict(a.params),
                          planned_start_s=a.start_s, planned_stop_s=a.stop_s, **extra)
        self.log(rec)
        return rec

    def halt(self, a: "Attack") -> None:
        """The family's time-critical stop now; the rest and the `stop` record in a worker."""
        if a.attack_id not in self.active:
            return
        try:
            finish = family(a.family).halt(self, a)
        finally:
            self.active.pop(a.attack_id, None)
        if self._pool is None:  # its threads start from a stop event: normal priority (SCHED_RESET_ON_FORK)
            self._pool = ThreadPoolExecutor(max_workers=4, thread_name_prefix="attack-stop")
        self._finishing[a.attack_id] = (a, self._pool.submit(self._finish, a, finish))

    def _finish(self, a: "Attack", finish: Callable[[], dict[str, Any]]) -> AttackStop:
        extra = finish()
        # a family may know better when its last packet can have crossed the network
        return self.log(AttackStop(attack_id=a.attack_id, family=a.family, t_unix=extra.pop("t_unix", time.time()),
                                   **extra))

    def _wait(self, attack_id: str) -> AttackStop | None:
        entry = self._finishing.pop(attack_id, None)
        if entry is None:
            return None
        try:
            return entry[1].result()
        except Exception as e:
            raise AttackError(f"{attack_id}: stop failed: {e}") from e

    def stop(self, a: "Attack") -> AttackStop | None:
        """Halt and finish now; the `stop` record."""
        self.halt(a)
        return self._wait(a.attack_id)

    def finish_all(self) -> None:
        """Wait for every halted stop to finish; raises the first error after all ended."""
        errors = []
        for aid in list(self._finishing):
            try:
                self._wait(aid)
            except AttackError as e:
                errors.append(str(e))
        if self._pool is not None:
            self._pool.shutdown(wait=True)
            self._pool = None
        if errors:
            raise AttackError("; ".join(errors))

    def calibrate(self, a: "Attack") -> None:
        family(a.family).calibrate(self, a)

    def stop_all(self) -> None:
        """Stop whatever is still running (end of run, or an interrupt); errors are kept, not raised."""
        for a in list(self.active.values()):
            try:
                self.stop(a)
            except Exception as e:
                self.errors.append(f"{a.attack_id}: stop failed: {e}")
        try:
            self.finish_all()
        except AttackError as e:
            self.errors.append(str(e))
        for proc in self.processes:
            proc.stop(signal.SIGTERM, grace_s=2.0)

    # forwarding ----------------------------------------------------------------------------
    def wormholes_for(self, window: "Window") -> list[Detour]:
        """Detours to apply with `window` given the attacks active now."""
        out: list[Detour] = []
        for a in self.active.values():
            out += family(a.family).overrides(self, a, window)
        return out

    def shape_overrides_for(self, window: "Window") -> list:
        """Link directions to shape otherwise with `window` given the attacks active now."""
        out: list = []
        for a in self.active.values():
            out += family(a.family).shaping_overrides(self, a, window)
        return out

    # the log -------------------------------------------------------------------------------
    def collect(self) -> list[AttackRecord]:
        """Read the attack processes' event logs (call before teardown: they live in the run dir)."""
        out: list[AttackRecord] = []
        for log in self.event_logs:
            if log.exists():
                out += read_attack_records(log)
        self.inject_records = out
        return out

    def log_lines(self) -> list[AttackRecord]:
        """Every record, in time order (stable: a stop's rate records stay before the stop)."""
        return sorted(self.records + self.inject_records, key=lambda r: r.t_unix)
