"""`realize(plan, out_dir) -> RunArtifacts`: play a Plan in real time on real Linux stacks.

Order of a run (t0 = wall-clock time of plan t = 0, written to run.json):
  namespaces + fabric + shaper (Emulation) -> one tcpdump per switch -> nginx on every UAV ->
  attack processes prepared (idle: replayers, floods behind their gates) -> window 0 applied ->
  t0 -> BS clients -> the schedule: window k at t0 + k * window_s, each attack's start/stop at
  t0 + start_s/stop_s (and a family's calibration times) -> end at t0 + duration -> attacks,
  clients and servers stopped -> captures stopped (SIGINT: flushed, drop counters read) ->
  namespaces removed.

Cleanup always happens: the Emulation context manager tears down on exceptions, SIGTERM/SIGHUP
(turned into SystemExit by the core) and Ctrl-C (KeyboardInterrupt); tools run in their own
sessions so Ctrl-C reaches only us and we stop them in order. After kill -9, `uavcas clean`
removes the run by its registry entry. The run directory's small files (attacks.jsonl,
shaping.jsonl, run.json: `uavcas.rundir.RunDir`) are written atomically in every case, run.json last, with the exit
status (0 ok, 130 SIGINT, 128+n other signals, 1 error).
"""

from __future__ import annotations

import json
import platform
import shutil
import statistics
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING

from uavcas.atomic import atomic_write_text
from uavcas.attacks import family
from uavcas.events import AttackLogged, Progress, RunDone, SetupDone, WindowApplied, attack_log_text
from uavcas.rundir import CaptureRecord, RunDir, RunInfo
from uavcas.versions import package_versions

from .apps import capture
from .apps.traffic import BenignTraffic
from .apps.versions import tool_versions
from .attacks import AttackExecutor
from .emulation import Emulation
from .naming import new_prefix
from .preflight import prepare_out_dir

if TYPE_CHECKING:
    from uavcas.twin.model import Plan

@dataclass(frozen=True)
class RunOptions:
    prefix: str | None = None  # namespace prefix (default: a fresh random one)
    telemetry: bool = False  # MAVLink-like UDP stream per UAV (off: the paper's traffic is HTTP)
    think_mean_s: float = 0.5  # mean pause between a BS's image fetches
    n_images: int = 24
    keep_logs: bool = True  # copy tool logs (curl results, stderr) to OUT/logs


@dataclass
class RunArtifacts:
    out_dir: Path
    t0_unix: float | None
    wall_s: float
    exit_status: int
    exit_reason: str
    pcaps: list[Path] = field(default_factory=list)
    capture: list[CaptureRecord] = field(default_factory=list)
    run_info: RunInfo | None = None

    @property
    def run_dir(self) -> RunDir:
        return RunDir(self.out_dir)


@dataclass(order=True)
class _Event:
    t_s: float
    prio: int  # at equal times: stop (0) < window (1) < start (2) < calibrate (3) < end (9)
    kind: str = field(compare=False)
    obj: object = field(compare=False, default=None)


def schedule(plan: "Plan") -> list[_Event]:
    ev = [_Event(w.t_s, 1, "window", w.index) for w in plan.windows[1:]]
    for a in plan.attacks:
        if a.stop_s <= a.start_s:  # empty window: nothing to do (and stop would precede start)
            continue
        ev += [_Event(a.start_s, 2, "start", a), _Event(a.stop_s, 0, "stop", a)]
        ev += [_Event(t, 3, "calibrate", a) for t in family(a.family).calibration_times(a)]
    ev.append(_Event(plan.duration_s, 9, "end"))
    return sorted(ev)


def realize(plan: "Plan", out_dir: str | Path, options: RunOptions = RunOptions(),
            on_event: Callable[[Progress], None] | None = None, features=None) -> RunArtifacts:
    """Realise `plan` into `out_dir` in real time (needs root). See the module docstring."""
    out = Path(out_dir)
    prefix = options.prefix or new_prefix()
    prepare_out_dir(out, prefix)  # refuses a directory that is not an old run's (RunDirError)
    atomic_write_text(RunDir(out).plan_json, plan.to_json())
    notify = on_event or (lambda e: None)
    st = _State(plan, out, time.time())
    try:
        with Emulation(plan, prefix=prefix, features=features) as emu:
            st.emu = emu
            st.timings["setup_s"] = time.time() - st.wall0
            notify(SetupDone(prefix=emu.prefix, seconds=st.timings["setup_s"]))
            try:
                _play(st, options, notify)
                st.exit_status, st.exit_reason = 0, "ok"
            finally:
                _wind_down(st, options)
            t = time.time()
        st.timings["teardown_s"] = time.time() - t
    except KeyboardInterrupt:
        st.exit_status, st.exit_reason = 130, "interrupted (SIGINT)"
    except SystemExit as e:
        st.exit_status = e.code if isinstance(e.code, int) else 1
        st.exit_reason = f"terminated by signal {st.exit_status - 128}" if st.exit_status > 128 else "exit"
        raise
    except BaseException as e:
        st.exit_status, st.exit_reason = 1, f"{type(e).__name__}: {e}"
        raise
    finally:
        _write_outputs(st)
        notify(RunDone(exit_status=st.exit_status, reason=st.exit_reason))
    return st.artifacts()


class _State:
    def __init__(self, plan: "Plan", out: Path, wall0: float) -> None:
        self.plan, self.out, self.wall0 = plan, out, wall0
        self.emu: Emulation | None = None
        self.t0: float | None = None
        self.timings: dict = {}
        self.windows: list[dict] = []
        self.shaping: list[dict] = []
        self.lateness_ms: list[float] = []
        self.events: list[dict] = []
        self.executor: AttackExecutor | None = None
        self.traffic: BenignTraffic | None = None
        self.captures: list[capture.Capture] = []
        self.capture_stats: list[CaptureRecord] = []
        self.clients: list[dict] = []
        self.delay_stats: dict | None = None
        self.exit_status, self.exit_reason = 1, "not finished"
        self.info: RunInfo | None = None
        self.wind_down_errors: list[str] = []

    def artifacts(self) -> RunArtifacts:
        return RunArtifacts(self.out, self.t0, time.time() - self.wall0, self.exit_status, self.exit_reason,
                            RunDir(self.out).pcaps(), self.capture_stats, self.info)


def _apply_window(st: _State, i: int) -> None:
    w = st.plan.windows[i]
    st.executor.window = w
    rep = st.emu.apply_links(w.links, st.executor.routes_for(w), st.executor.wormholes_for(w), window_index=w.index)
    st.shaping += [r.to_dict() for r in rep.records]
    st.windows.append({"window": w.index, "t_unix": time.time(), "links_up": rep.links_up,
                       "links_down": rep.links_down, "fdb_changes": rep.fdb_changes, "rejected": rep.rejected,
                       "timings_s": {k: round(v, 6) for k, v in rep.timings_s.items()}})


def _play(st: _State, opt: RunOptions, notify: Callable[[Progress], None]) -> None:
    plan, emu = st.plan, st.emu
    work = emu.naming.run_dir / "apps"
    dur = plan.duration_s
    t = time.time()
    st.captures = capture.start_all(emu, [n.name for n in plan.nodes], RunDir(st.out).pcap_dir, work / "logs",
                                    dur + 120)
    st.traffic = BenignTraffic(emu, plan, work, dur, telemetry_on=opt.telemetry, think_mean_s=opt.think_mean_s,
                               n_images=opt.n_images)
    st.traffic.start_servers()
    st.executor = AttackExecutor(emu, plan, work, dur, on_event=lambda r: notify(AttackLogged(record=r)))
    st.executor.prepare()
    st.timings["apps_s"] = time.time() - t
    _apply_window(st, 0)
    st.t0 = time.time()
    notify(WindowApplied(window=0, t0_unix=st.t0, n_windows=len(plan.windows)))
    st.traffic.start_clients()
    for ev in schedule(plan):
        target = st.t0 + ev.t_s
        time.sleep(max(0.0, target - time.time()))
        late_ms = (time.time() - target) * 1000
        st.lateness_ms.append(late_ms)
        t_ev = time.time()
        if ev.kind == "window":
            _apply_window(st, ev.obj)
            notify(WindowApplied(window=ev.obj, n_windows=len(plan.windows)))
        elif ev.kind == "start":
            st.executor.start(ev.obj)
        elif ev.kind == "stop":
            st.executor.stop(ev.obj)
        elif ev.kind == "calibrate":
            st.executor.calibrate(ev.obj)
        st.events.append({"t_s": ev.t_s, "kind": ev.kind, "what": getattr(ev.obj, "attack_id", ev.obj),
                          "late_ms": round(late_ms, 3), "took_ms": round((time.time() - t_ev) * 1000, 3)})
    st.timings["schedule_s"] = time.time() - st.t0
    emu.shaper.check()  # a delay stage lost in the last window fails the run too


def _wind_down(st: _State, opt: RunOptions) -> None:
    """Stop everything in order, keeping going past errors (the core's teardown is the backstop)."""
    t = time.time()
    errors = []
    for step in (lambda: st.executor and st.executor.stop_all(),
                 lambda: st.executor and st.executor.collect(),
                 lambda: st.traffic and setattr(st, "clients", [c.to_dict() for c in st.traffic.stop()]),
                 lambda: setattr(st, "delay_stats", _delay_stats(st.emu)),
                 lambda: setattr(st, "capture_stats", capture.stop_all(st.captures))):
        try:
            step()
        except Exception as e:
            errors.append(f"{type(e).__name__}: {e}")
    if st.executor:
        errors += st.executor.errors
    if opt.keep_logs and st.emu is not None:
        logs = st.emu.naming.run_dir / "apps" / "logs"
        if logs.is_dir():
            shutil.copytree(logs, RunDir(st.out).logs_dir, dirs_exist_ok=True)
    st.timings["stop_s"] = time.time() - t
    st.wind_down_errors = errors


def _delay_stats(emu: Emulation) -> dict | None:
    stats = getattr(emu.shaper, "daemon_stats", None)
    return stats() if stats and getattr(emu.shaper, "daemon", None) else None


def _write_outputs(st: _State) -> None:
    ex = st.executor
    rd = RunDir(st.out)
    atomic_write_text(rd.attacks_jsonl, attack_log_text(ex.log_lines() if ex else []))
    atomic_write_text(rd.shaping_jsonl, "".join(json.dumps(r) + "\n" for r in st.shaping))
    emu = st.emu
    lat = st.lateness_ms
    drops = [c.dropped_by_kernel for c in st.capture_stats]
    now = time.time()
    st.info = RunInfo(
        config=st.plan.config, seed=st.plan.seed, windows=len(st.plan.windows), window_s=st.plan.window_s,
        prefix=emu.prefix if emu else None, t0_unix=st.t0, t_end_unix=now, wall_s=round(now - st.wall0, 3),
        exit_status=st.exit_status, exit_reason=st.exit_reason,
        versions=package_versions("scapy", "dpkt", "pydantic"), tool_versions=tool_versions(),
        kernel=platform.release(),
        kernel_features=emu.features.to_dict() if emu else None, shaper_backend=emu.backend if emu else None,
        timings={**{k: round(v, 4) for k, v in st.timings.items()},
                 "schedule_lateness_ms": {"max": round(max(lat), 3), "mean": round(statistics.fmean(lat), 3)}
                 if lat else None},
        window_applies=st.windows,
        schedule=st.events,
        capture=st.capture_stats,
        capture_drops=sum(d for d in drops if d) if st.capture_stats else None,
        packets_captured=sum(c.captured or 0 for c in st.capture_stats),
        http_clients=st.clients, delay_daemon=st.delay_stats,
        attack_errors=ex.errors if ex else [],
        wind_down_errors=st.wind_down_errors,
    )
    atomic_write_text(rd.run_json, st.info.to_json())
