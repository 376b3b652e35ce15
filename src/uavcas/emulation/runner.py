"""`realize(plan, out_dir) -> RunArtifacts`: play a Plan in real time on real Linux stacks.

Order of a run (t0 = wall-clock time of plan t = 0, written to run.json):
  namespaces + fabric + shaper (Emulation) -> one tcpdump per switch -> the servers of the payload's
  traffic apps (`uavcas.traffic`: MAVLink endpoints, video sinks, nginx on every UAV) ->
  attack processes prepared (idle: replayers, floods behind their gates) -> window 0 applied ->
  t0 -> the apps' clients (MAVLink endpoints released, video senders, BS curl loops, in the
  payload's order: `traffic.benign`) -> the schedule: window k at t0 + k * window_s, each attack's start/stop at
  t0 + start_s/stop_s (and a family's calibration times) -> end at t0 + duration -> attacks,
  clients and servers stopped -> captures stopped (SIGINT: flushed, drop counters read) ->
  namespaces removed.

Cleanup always happens: the Emulation context manager tears down on exceptions, SIGTERM/SIGHUP
(turned into SystemExit by the core) and Ctrl-C (KeyboardInterrupt); tools run in their own
sessions so Ctrl-C reaches only us and we stop them in order. After kill -9, `uavcas clean`
removes the run by its registry entry. The run directory's small files (attacks.jsonl,
shaping.jsonl, run.json: `uavcas.rundir.RunDir`) are written atomically in every case, run.json last, with the exit
status (0 ok, 130 SIGINT, 128+n other signals, 1 error).

The runner does not audit the run: its callers do, after it returns (`uavcas.fidelity.audit_run`,
stage 2b: `uavcas run` and the campaign worker), so this package does not import the audit.
"""

from __future__ import annotations

import json
import platform
import shutil
import statistics
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING

from uavcas.atomic import atomic_write_text
from uavcas.attacks import family
from uavcas.events import AttackLogged, Progress, RunDone, SetupDone, WindowApplied, attack_log_text
from uavcas.network.naming import new_prefix
from uavcas.rundir import CaptureRecord, RunDir, RunInfo
from uavcas.traffic.base import AppOptions
from uavcas.traffic.benign import BenignTraffic
from uavcas.traffic.video import BITRATE_KBPS
from uavcas.versions import package_versions

from .apps import capture
from .apps.versions import tool_versions
from .attacks import AttackExecutor
from .emulation import Emulation
from .preflight import prepare_out_dir
from .priority import CONTROL_RT_PRIORITY, SOFTIRQ_RT_PRIORITY, softirq_boost, urgent
from .sampling import WindowSampler

if TYPE_CHECKING:
    from uavcas.twin.model import Plan

LINKS_READY_S = 10.0  # longest wait for window 0's links to become operational (before t0)
PREPARE_MARGIN_S = 0.05  # preparing the next window stops this long before the next event


@dataclass(frozen=True)
class RunOptions:
    prefix: str | None = None  # namespace prefix (default: a fresh random one)
    think_mean_s: float = 0.5  # mean pause between a BS's image fetches
    n_images: int = 24
    video_kbps: int = BITRATE_KBPS  # H.264 bitrate of each UAV's video (the video app; traffic/video.py)
    mavlink_signing: bool = False  # MAVLink 2 signing between GCS and UAV endpoints (traffic/mavlink/signing.py)
    keep_logs: bool = True  # copy tool logs (curl results, stderr) to OUT/logs
    urgent: bool = True  # window changes and attack actions at real-time priority (emulation.priority)
    softirq_boost: bool = True  # the kernel's softirq threads at real-time priority during the run


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
    notify = _serialised(on_event or (lambda e: None))  # attack stops finish in worker threads
    st = _State(plan, out, time.time())
    try:
        with Emulation(plan, prefix=prefix, features=features, readback=False) as emu:
            st.emu = emu
            emu.keep_links_up = True  # see _prepare_next
            st.sampler = WindowSampler(emu.shaper)
            st.timings["setup_s"] = time.time() - st.wall0
            notify(SetupDone(prefix=emu.prefix, seconds=st.timings["setup_s"]))
            try:
                with softirq_boost(emu.prefix, SOFTIRQ_RT_PRIORITY if options.softirq_boost else 0):
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
        self.streams: dict | None = None
        self.delay_stats: dict | None = None
        self.sampler: WindowSampler | None = None
        self.starter: _Background | None = None  # the clients' start, in the background
        self.exit_status, self.exit_reason = 1, "not finished"
        self.info: RunInfo | None = None
        self.wind_down_errors: list[str] = []

    def artifacts(self) -> RunArtifacts:
        return RunArtifacts(self.out, self.t0, time.time() - self.wall0, self.exit_status, self.exit_reason,
                            RunDir(self.out).pcaps(), self.capture_stats, self.info)


def _apply_window(st: _State, i: int) -> None:
    w = st.plan.windows[i]
    st.executor.window = w
    jammed = st.executor.shape_overrides_for(w)  # links an active attack shapes otherwise (jamming)
    rep = st.emu.apply_links(w.links, [r.hops for r in w.routes], st.executor.wormholes_for(w), window_index=w.index,
                             overrides=jammed)
    st.sampler.window_applied(w.index, st.emu.shapes(w.links, jammed))
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
    st.traffic = BenignTraffic(emu, plan, work, dur, options=AppOptions(
        think_mean_s=opt.think_mean_s, n_images=opt.n_images, video_kbps=opt.video_kbps,
        mavlink_signing=opt.mavlink_signing))
    st.traffic.start_servers()
    st.executor = AttackExecutor(emu, plan, work, dur, on_event=lambda r: notify(AttackLogged(record=r)))
    st.executor.on_reshape = st.sampler.window_applied  # a mid-window reshape starts a counter segment
    st.executor.prepare()
    st.timings["apps_s"] = time.time() - t
    with urgent(CONTROL_RT_PRIORITY if opt.urgent else 0):
        t_links = time.time()
        _plan_change(st, 0)  # window 0's forwarding and FDB batch planned first, as for every later window
        _, ready = emu.prepare_links(plan.windows[0].links, wait_s=LINKS_READY_S)
        st.timings["links_ready_s"] = time.time() - t_links
        if not ready:
            st.wind_down_errors.append(f"window 0: links not operational after {LINKS_READY_S:g} s")
        _apply_window(st, 0)
    st.t0 = time.time()
    # Recorded at once: a run killed before it writes run.json can still be placed in its plan.
    rd = RunDir(st.out)
    owner = rd.read_owner()
    if owner is not None:
        rd.write_owner(owner.model_copy(update={"t0_unix": st.t0}))
    notify(WindowApplied(window=0, t0_unix=st.t0, n_windows=len(plan.windows)))
    # Starting a hundred client loops took 6 s on a loaded machine: in the background, so that the
    # schedule (window 1 at t0 + 5 s) never waits for it.
    t0 = st.t0
    starter = st.starter = _Background(lambda: st.traffic.start_clients(t0))
    events = schedule(plan)
    _prepare_next(st, opt, events)
    for k, ev in enumerate(events):
        target = st.t0 + ev.t_s
        # sleeping at real-time priority too: the wake-up is not queued behind the load
        with urgent(CONTROL_RT_PRIORITY if opt.urgent else 0, inherit=ev.kind == "window"):
            time.sleep(max(0.0, target - time.time()))
            late_ms = (time.time() - target) * 1000
            t_ev = time.time()
            if ev.kind == "window":
                _apply_window(st, ev.obj)
            elif ev.kind == "start":
                st.executor.start(ev.obj)
            elif ev.kind == "stop":
                st.executor.halt(ev.obj)  # its bookkeeping goes on in a worker: the next event is not kept waiting
            elif ev.kind == "calibrate":
                st.executor.calibrate(ev.obj)
            took_ms = (time.time() - t_ev) * 1000
        st.lateness_ms.append(late_ms)
        st.events.append({"t_s": ev.t_s, "kind": ev.kind, "what": getattr(ev.obj, "attack_id", ev.obj),
                          "late_ms": round(late_ms, 3), "took_ms": round(took_ms, 3)})
        if ev.kind == "window":
            notify(WindowApplied(window=ev.obj, n_windows=len(plan.windows)))
        elif ev.kind == "end":
            st.sampler.end()
        _prepare_next(st, opt, events[k + 1:])
    st.timings["schedule_s"] = time.time() - st.t0
    st.executor.finish_all()
    starter.join()
    st.emu.shaper.check()  # a delay stage lost in the last window fails the run too


def _serialised(fn: Callable[[Progress], None]) -> Callable[[Progress], None]:
    lock = threading.Lock()

    def call(e: Progress) -> None:
        with lock:
            fn(e)

    return call


class _Background:
    """A call in a thread; `join()` waits for it and raises what it raised."""

    def __init__(self, fn: Callable[[], object]) -> None:
        self.error: BaseException | None = None
        self.thread = threading.Thread(target=self._run, args=(fn,), daemon=True)
        self.thread.start()

    def _run(self, fn: Callable[[], object]) -> None:
        try:
            fn()
        except BaseException as e:  # handed to the main thread by join()
            self.error = e

    def join(self) -> None:
        self.thread.join()
        if self.error is not None:
            raise self.error


def _plan_change(st: _State, i: int) -> None:
    """Plan window i's change in idle time, with the arguments `_apply_window` will give it."""
    w = st.plan.windows[i]
    st.emu.plan_change(w.links, [r.hops for r in w.routes], st.executor.wormholes_for(w))


def _prepare_next(st: _State, opt: RunOptions, upcoming: list[_Event]) -> None:
    """Between events: raise the next window's new links and compute its forwarding and FDB batch,
    so that the change itself neither waits for them nor drops frames on links not yet operational.

    Links that left the plan stay up, with no forwarding entry pointing at them (no frame
    reaches them): taking a port down costs ~30 ms under load (an RCU grace period each), which
    would only delay the schedule.
    """
    nxt = next((e for e in upcoming if e.kind == "window"), None)
    if nxt is None:
        return
    w = st.plan.windows[nxt.obj]
    until = st.t0 + upcoming[0].t_s - PREPARE_MARGIN_S  # never delay the next event
    t = time.time()
    with urgent(CONTROL_RT_PRIORITY if opt.urgent else 0):
        _plan_change(st, nxt.obj)
        raised, ready = st.emu.prepare_links(w.links, wait_s=max(0.0, until - time.time()))
    if not ready and upcoming[0] is nxt:
        st.wind_down_errors.append(f"window {nxt.obj}: links not operational when it began")
    if raised:
        st.events.append({"t_s": round(t - st.t0, 6), "kind": "prepare", "what": nxt.obj, "late_ms": 0.0,
                          "took_ms": round((time.time() - t) * 1000, 3)})


def _wind_down(st: _State, opt: RunOptions) -> None:
    """Stop everything in order, keeping going past errors (the core's teardown is the backstop)."""
    t = time.time()
    errors = []
    for step in (lambda: st.starter and st.starter.thread.join(60.0),  # no client starts after the stop
                 lambda: st.executor and st.executor.stop_all(),
                 lambda: st.executor and st.executor.collect(),
                 lambda: st.traffic and _stop_traffic(st),
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
        daemon_log = st.emu.naming.run_dir / "nfqdelay.log"
        if daemon_log.is_file():
            RunDir(st.out).logs_dir.mkdir(exist_ok=True)
            shutil.copy(daemon_log, RunDir(st.out).logs_dir / daemon_log.name)
    st.timings["stop_s"] = time.time() - t
    st.wind_down_errors += errors


def _delay_stats(emu: Emulation) -> dict | None:
    stats = getattr(emu.shaper, "daemon_stats", None)
    return stats() if stats and getattr(emu.shaper, "daemon", None) else None


def _stop_traffic(st: _State) -> None:
    st.clients = st.traffic.stop()
    st.streams = st.traffic.streams_summary()


def _write_outputs(st: _State) -> None:
    ex = st.executor
    rd = RunDir(st.out)
    atomic_write_text(rd.attacks_jsonl, attack_log_text(ex.log_lines() if ex else []))
    if st.sampler is not None:
        st.shaping = [r.to_dict() for r in st.sampler.close()]
        st.wind_down_errors += st.sampler.errors
    atomic_write_text(rd.shaping_jsonl, "".join(json.dumps(r) + "\n" for r in st.shaping))
    emu = st.emu
    if emu is not None:
        atomic_write_text(rd.forwarding_jsonl, "".join(e.model_dump_json() + "\n" for e in emu.forwarding_log))
    lat = st.lateness_ms
    drops = [c.dropped_by_kernel for c in st.capture_stats]
    now = time.time()
    st.info = RunInfo(
        config=st.plan.config, seed=st.plan.seed, windows=len(st.plan.windows), window_s=st.plan.window_s,
        prefix=emu.prefix if emu else None, t0_unix=st.t0, t_end_unix=now, wall_s=round(now - st.wall0, 3),
        exit_status=st.exit_status, exit_reason=st.exit_reason,
        versions=package_versions("scapy", "pydantic", "pymavlink"), tool_versions=tool_versions(),
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
        http_clients=st.clients, streams=st.streams, delay_daemon=st.delay_stats,
        attack_errors=ex.errors if ex else [],
        wind_down_errors=st.wind_down_errors,
        profile=st.plan.profile, profile_sha256=st.plan.profile_sha256,
        # whether the run's MAVLink was signed (never the key): off when no payload carries MAVLink
        mavlink_signing=bool(st.traffic and st.traffic.mavlink_signed),
    )
    atomic_write_text(rd.run_json, st.info.to_json())
