"""`Emulation(plan)`: realise a Plan's hosts, switches and links on this kernel, window by window.

    with Emulation(plan, prefix="uc1234") as emu:   # setup() on enter, teardown() always
        for i in range(len(plan.windows)):
            report = emu.apply_window(i)           # links, shaping, forwarding; read back
            emu.popen("uav0", ["nginx", ...])      # processes inside a node namespace

Teardown runs on exit, on exceptions, on SIGTERM/SIGHUP (turned into SystemExit), on SIGINT
(KeyboardInterrupt, even when the parent started us with SIGINT ignored) and at interpreter
exit; after SIGKILL, `uavcas clean` uses the run's registry entry.
"""

from __future__ import annotations

import atexit
import os
import signal
import subprocess
import threading
import time
from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Literal

if TYPE_CHECKING:  # only typed against the plan: importing uavcas.twin pulls the whole planner
    from uavcas.twin.model import Link, LinkOverride, Plan

from uavcas.network.forwarding import Detour, Forwarding, compute
from uavcas.network.naming import Naming, new_prefix
from uavcas.rundir import ForwardingEpoch

from . import cleanup, kernel
from .fabric import Fabric, LinkKey, SwitchPorts, key
from .hosts import IPV6_OFF, Hosts, HostSpec
from .probe import Features, probe
from .shaping import Shape, Shaper, ShapingRecord, make_shaper

FABRIC_SYSCTLS = {**IPV6_OFF, "net.bridge.bridge-nf-call-iptables": 1,
                  "net.bridge.bridge-nf-call-ip6tables": 0, "net.bridge.bridge-nf-call-arptables": 0}
LinkMode = Literal["plan", "all", "lazy"]


@dataclass
class WindowReport:
    window: int
    timings_s: dict[str, float]
    links_up: int
    links_down: int
    links_created: int
    fdb_changes: int
    rejected: list[str]
    records: list[ShapingRecord] = field(default_factory=list)

    @property
    def total_s(self) -> float:
        return self.timings_s.get("total_s", 0.0)


class Emulation:
    """One run's namespaces, fabric and shaping. See the module docstring."""

    def __init__(self, plan: "Plan", prefix: str | None = None, *, cpu_cap: float | None = None,
                 links: LinkMode = "plan", backend: str | None = None, readback: bool = True,
                 features: Features | None = None) -> None:
        self.plan = plan
        self.naming = Naming(prefix or new_prefix())
        self.prefix = self.naming.prefix
        self.features = features or probe()
        self.backend = backend or self.features.shaper
        self.cpu_cap = cpu_cap
        self.link_mode = links
        self.readback = readback
        self.specs = [HostSpec(n.name, n.index, n.ip, n.mac, self.naming.node_ns(n.name)) for n in plan.nodes]
        if [s.index for s in self.specs] != list(range(len(self.specs))):
            raise ValueError("plan node indices must be 0..n-1 in order")
        self.names = [s.name for s in self.specs]
        self.index = {s.name: s.index for s in self.specs}
        self.hosts = Hosts(self.naming, self.specs, self.features.cgroup)
        self.shaper: Shaper = make_shaper(self.backend, self.naming.fabric_ns, self.naming.run_dir)
        self.fabric = Fabric(self.naming, self.specs, self.shaper)
        self.window: int | None = None
        self.forwarding: Forwarding | None = None
        self.forwarding_log: list[ForwardingEpoch] = []  # every table installed, with when
        self._fwd_memo: dict[tuple, Forwarding] = {}
        self._active: set[LinkKey] = set()  # links of the last apply
        self._prepared: set[LinkKey] = set()  # raised ahead of the next window (prepare_links)
        self.keep_links_up = False  # see apply_links
        self._links: list["Link"] = []
        self._routes: list[list[str]] = []
        self._wormholes: list[Detour] = []
        self._procs: list[subprocess.Popen] = []
        self._lock: cleanup.RunLock | None = None
        self._old_handlers: dict[int, object] = {}
        self._torn_down = True

    # lifecycle ---------------------------------------------------------------------------
    @property
    def namespaces(self) -> list[str]:
        return [self.naming.fabric_ns, *self.hosts.namespaces]

    def setup(self) -> dict[str, float]:
        if not self.features.root or not self.features.netns:
            raise kernel.KernelError("emulation needs root and network namespaces")
        t0 = time.perf_counter()
        cgroups = self.hosts.caps.planned_dirs(self.names) if self.cpu_cap else []
        self._lock = cleanup.RunLock(cleanup.RunRecord(self.prefix, os.getpid(),
                                                       self.namespaces, cgroups))
        self._torn_down = False
        atexit.register(self.teardown)
        try:
            # Leftovers of a crashed run with this very prefix: ours to remove, since we hold the
            # prefix's lock (a live run would hold it).
            cleanup.remove_namespaces(sorted(set(self.namespaces) & set(kernel.netns_list())))
            kernel.run_batch("ip", None, [f"netns add {ns}" for ns in self.namespaces])
            # IPv6 off before any interface exists: no DAD/RS/MLD frames ever (storm trap).
            kernel.write_sysctls(self.naming.fabric_ns, FABRIC_SYSCTLS)
            for ns in self.hosts.namespaces:
                kernel.write_sysctls(ns, IPV6_OFF)
            self.shaper.start()  # loss table before any port; the delay daemon boots meanwhile
            t1 = time.perf_counter()
            fab = self.fabric.setup(self._precreate())
            t2 = time.perf_counter()
            self.hosts.configure()
            if self.cpu_cap:
                self.hosts.cap_cpu(self.cpu_cap)
            t3 = time.perf_counter()
            self.shaper.wait_ready()
            t4 = time.perf_counter()
        except BaseException:
            self.teardown()
            raise
        return {"netns_and_shaper_s": t1 - t0, **fab, "hosts_s": t3 - t2, "wait_daemon_s": t4 - t3,
                "total_s": t4 - t0}

    def _precreate(self) -> list[LinkKey]:
        n = len(self.specs)
        if self.link_mode == "all":
            return [(i, j) for i in range(n) for j in range(i + 1, n)]
        if self.link_mode == "lazy":
            return []
        keys = {key(self.index[lk.a], self.index[lk.b]) for w in self.plan.windows for lk in w.links}
        return sorted(keys)

    def teardown(self) -> dict[str, float]:
        if self._torn_down:
            return {}
        self._torn_down = True
        t0 = time.perf_counter()
        try:
            self.shaper.stop()
        finally:
            pids = [p.pid for p in self._procs if p.poll() is None]
            cleanup.kill_pids(pids, grace_s=1.0)
            for p in self._procs:
                try:
                    p.wait(0.5)
                except subprocess.TimeoutExpired:
                    pass
            cleanup.remove_namespaces(self.namespaces)
            cleanup.remove_cgroups(self.hosts.caps.planned_dirs(self.names))
            if self._lock is not None:
                self._lock.release()
                self._lock = None
            atexit.unregister(self.teardown)
        return {"total_s": time.perf_counter() - t0}

    def __enter__(self) -> "Emulation":
        if threading.current_thread() is threading.main_thread():
            for sig in (signal.SIGTERM, signal.SIGHUP):
                self._old_handlers[sig] = signal.signal(sig, _raise_exit)
            # A shell without job control starts background jobs with SIGINT ignored, and Python
            # then never raises KeyboardInterrupt: `kill -INT` would be lost and the run would
            # end "ok". A run must stop on SIGINT (exit 130), so Ctrl-C is turned on here.
            if signal.getsignal(signal.SIGINT) in (signal.SIG_IGN, signal.SIG_DFL, None):
                self._old_handlers[signal.SIGINT] = signal.signal(signal.SIGINT, signal.default_int_handler)
        self.setup()
        return self

    def __exit__(self, *exc: object) -> None:
        try:
            self.teardown()
        finally:
            for sig, h in self._old_handlers.items():
                signal.signal(sig, h)
            self._old_handlers.clear()

    # windows -------------------------------------------------------------------------------
    def apply_window(self, i: int) -> WindowReport:
        w = self.plan.windows[i]
        report = self.apply_links(w.links, [r.hops for r in w.routes],
                                  [Detour.of((o.victim, o.attacker, o.bs), o.hops) for o in w.wormholes],
                                  window_index=w.index)
        self.window = i
        return report

    def apply_links(self, links: Sequence["Link"], routes: Iterable[Sequence[str]] = (),
                    wormholes: Iterable["Detour | Sequence[str]"] = (), window_index: int = -1,
                    overrides: Sequence["LinkOverride"] = ()) -> WindowReport:
        """Make `links` (and only them) active with their shaping (`overrides`: directions shaped
        otherwise, see `shapes`), then forwarding for them, with the given wormhole detours
        diverting (`uavcas.network.forwarding`).

        With `keep_links_up` set, links that leave the window stay up (no forwarding entry
        points at them, so no frame reaches them; taking a port down waits for an RCU grace
        period, ~30 ms each under load, which a window change need not wait for). Links raised
        ahead by `prepare_links` for a later window stay up either way.
        """
        t0 = time.perf_counter()
        self.shaper.check()
        self._links, self._routes = list(links), [list(r) for r in routes]
        self._wormholes = [Detour.of(w) for w in wormholes]
        active = {key(self.index[lk.a], self.index[lk.b]) for lk in links}
        created = self.fabric.ensure_links(active)
        t1 = time.perf_counter()
        shapes = self.shapes(links, overrides)
        keep = self._prepared - active  # raised ahead for the next window (prepare_links): stay up
        down, up = self.fabric.toggle_lines(active | keep)
        if self.keep_links_up:
            down = []
        n_up, n_down = len(active - self._active), len(self._active - active)
        self.forwarding = self.plan_forwarding(links, self._routes, self._wormholes)
        want, fdb = self.fabric.plan_update(self.forwarding)
        t2 = time.perf_counter()
        stopping = self._stopping_detours()
        if stopping:
            self.fabric.apply_detours(self.forwarding.detours)
        # Two concurrent phases: (1) shaping in place + links going down; (2) links coming up +
        # forwarding. A link is thus shaped before its first frame, and traffic only loses the
        # few milliseconds between the phases on paths that change.
        t_begin = time.time()
        stage = self.shaper.apply(shapes, also=[kernel.Batch("ip", self.fabric.ns, down)])
        t3 = time.perf_counter()
        kernel.run_batches([kernel.Batch("ip", self.fabric.ns, up), kernel.Batch("bridge", self.fabric.ns, fdb)])
        self.fabric.up = (self.fabric.up if self.keep_links_up else set()) | active | keep
        self.fabric.fdb = want
        self._active, self._prepared = active, keep
        if not stopping:
            self.fabric.apply_detours(self.forwarding.detours)
        self._log_forwarding(t_begin, window_index)
        t4 = time.perf_counter()
        timings = {"create_s": t1 - t0, "compute_s": t2 - t1, "phase1_s": t3 - t2, **stage, "phase2_s": t4 - t3,
                   "total_s": t4 - t0}
        fdb_changes = len(fdb)
        records: list[ShapingRecord] = []
        if self.readback:
            applied = self.shaper.readback([s.port for s in shapes])
            records = self.shaper.records(window_index, shapes, applied)
            timings["readback_s"] = time.perf_counter() - t4
        return WindowReport(window_index, timings, n_up, n_down, created, fdb_changes, self.forwarding.rejected,
                            records)

    def prepare_links(self, links: Sequence["Link"], wait_s: float = 1.0) -> tuple[int, bool]:
        """Create and raise, ahead of their window, the links of `links` that are not up yet, and
        wait up to `wait_s` for every link prepared so far to be operational (call it again to
        wait more).

        A raised link carries nothing until the forwarding points at it (flooding and learning
        are off), and the kernel attaches a port's queue only once its link-watch work has seen
        the carrier (up to seconds on a loaded machine; frames sent before are dropped): raising
        links in idle time and waiting here keeps that off the window change. Returns how many,
        and whether they all became operational within `wait_s`.
        """
        active = {key(self.index[lk.a], self.index[lk.b]) for lk in links}
        self.fabric.ensure_links(active)
        new = sorted(active - self.fabric.up)
        if new:
            kernel.run_batch("ip", self.fabric.ns, [f"link set {p} up" for p in Fabric._ports(new)])
            self.fabric.up |= set(new)
        self._prepared = (self._prepared | set(new)) & active
        waiting = Fabric._ports(sorted(self._prepared))
        ok = self.fabric.wait_operational(waiting, wait_s) if waiting else True
        return len(new), ok

    def plan_forwarding(self, links: Sequence["Link"], routes: Iterable[Sequence[str]] = (),
                        wormholes: Iterable["Detour | Sequence[str]"] = ()) -> Forwarding:
        """The forwarding for these links, routes and detours (memoised: a runner computes the
        next window's ahead, in idle time, so that the change itself does not wait for it)."""
        links = list(links)
        key = (tuple((lk.a, lk.b) for lk in links), tuple(tuple(r) for r in routes),
               tuple(Detour.of(w) for w in wormholes), tuple((lk.a, lk.b) for lk in links if lk.detour))
        fwd = self._fwd_memo.get(key)
        if fwd is None:
            if len(self._fwd_memo) > 8:
                self._fwd_memo.clear()
            fwd = self._fwd_memo[key] = compute(self.names, list(key[0]), key[1], key[2], key[3])
        return fwd

    def plan_change(self, links: Sequence["Link"], routes: Iterable[Sequence[str]] = (),
                    wormholes: Iterable["Detour | Sequence[str]"] = ()) -> None:
        """Compute ahead, in idle time, the forwarding and the FDB batch `apply_links` will need
        for these links from the current FDB (`Fabric.plan_update`): the change only replays it."""
        self.fabric.plan_update(self.plan_forwarding(links, routes, wormholes))

    def shapes(self, links: Sequence["Link"], overrides: Sequence["LinkOverride"] = ()) -> list[Shape]:
        """Both directions of every link with its parameters, except the directions (src, dst)
        of `overrides`, which take the override's rate, delay and loss (a jammed link)."""
        other = {(o.src, o.dst): o for o in overrides}
        out = []
        for lk in links:
            i, j = self.index[lk.a], self.index[lk.b]
            for src, dst, a, b in ((lk.a, lk.b, i, j), (lk.b, lk.a, j, i)):
                p = other.get((src, dst), lk)
                out.append(Shape(src, dst, Naming.link_port(a, b), p.rate_mbps, p.delay_ms, p.loss))
        return out

    def reshape(self, links: Sequence["Link"], overrides: Sequence["LinkOverride"] = ()) -> list[Shape]:
        """Shaping alone (no link or forwarding change) to the current links with `overrides`:
        the ports whose parameters change, in one tc batch and one nft batch (`Shaper.apply`).
        Returns every shape now in force."""
        self.shaper.check()
        shapes = self.shapes(links, overrides)
        self.shaper.apply(shapes)
        return shapes

    def set_wormholes(self, detours: Iterable["Detour | Sequence[str]"]) -> int:
        """Re-route the current links with these wormhole detours (FDB and detour table only)."""
        self._wormholes = [Detour.of(d) for d in detours]
        self.forwarding = self.plan_forwarding(self._links, self._routes, self._wormholes)
        t_begin = time.time()
        stopping = self._stopping_detours()
        if stopping:
            self.fabric.apply_detours(self.forwarding.detours)
        changes = self.fabric.apply_forwarding(self.forwarding)
        if not stopping:
            self.fabric.apply_detours(self.forwarding.detours)
        self._log_forwarding(t_begin, self.forwarding_log[-1].window if self.forwarding_log else -1)
        return changes

    def _stopping_detours(self) -> bool:
        """True when the new detours are a subset of those diverting now: the table changes first
        (a detour stops diverting before anything else moves); otherwise after the FDB, so a new
        detour diverts only once its path is in place (alias entries outlive their detour, so
        frames already diverted still arrive)."""
        return {(d.victim, d.bs) for d in self.forwarding.detours} <= set(self.fabric.detours_active)

    def _log_forwarding(self, t_begin: float, window: int) -> None:
        self.forwarding_log.append(ForwardingEpoch(t_begin_unix=t_begin, t_unix=time.time(), window=window,
                                                   next_hop=self.forwarding.next_hop,
                                                   detours={d.key: list(d.hops) for d in self.forwarding.detours}))

    # processes and hooks -------------------------------------------------------------------
    def ns(self, node: str) -> str:
        return self.naming.node_ns(node)

    @property
    def fabric_ns(self) -> str:
        return self.naming.fabric_ns

    def popen(self, node: str, argv: Sequence[str], timeout_s: float | None = None, **kw) -> subprocess.Popen:
        """Start argv inside node's namespace (and CPU cgroup); stopped by PID at teardown."""
        p = self.hosts.popen(node, argv, timeout_s, **kw)
        self._procs.append(p)
        return p

    def run(self, node: str, argv: Sequence[str], timeout_s: float = 30.0, **kw) -> subprocess.CompletedProcess:
        return self.hosts.run(node, argv, timeout_s, **kw)

    def popen_fabric(self, argv: Sequence[str], timeout_s: float | None = None, **kw) -> subprocess.Popen:
        """Start argv in the fabric namespace (e.g. tcpdump on a switch); stopped at teardown."""
        p = self.fabric.popen(argv, timeout_s, **kw)
        self._procs.append(p)
        return p

    def switch(self, node: str) -> SwitchPorts:
        return self.fabric.switch(node)

    def ip(self, node: str) -> str:
        return self.plan.node(node).ip


def _raise_exit(signum: int, _frame: object) -> None:
    raise SystemExit(128 + signum)
