"""Execute a plan's attack schedule on a running Emulation and write the attack log.

The runner calls `start(attack)` / `stop(attack)` at the planned times (and `calibrate` one
second into a flood); this module does the work per family and records what happened:

* dos / ddos: one `apps.flood.Flood` (hping3 -S to the victim's HTTP port) per attacker;
  a `rate` record per attacker with the measured SYN rate;
* blackhole: an nft bridge table on the victim's switch drops the victim's IPv4 frames in both
  directions, ARP untouched (`apps.hooks`); deleted at stop (its drop count is logged);
* wormhole: the plan's override (victim <-> its BS through the attacker's switch) is laid into
  the static FDB at start and removed at stop; `wormholes_for(window)` tells the runner which
  overrides to keep when a window changes mid-attack. The detour's links are the plan's, so
  the extra hop is shaped like any other;
* replay: the replayer process is started before t0 (scapy takes a second to import) and sees
  nothing of the victim until `start` mirrors the victim's host port to the attacker's; at stop
  the mirror is removed and the process ended before `stop` is logged.

Times: a `start` record's t_unix is taken just *before* the action and a `stop` record's just
*after* it is fully undone, so every attack packet and effect lies inside [start, stop).
"""

from __future__ import annotations

import json
import signal
import sys
import time
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING

from .apps import hooks
from .apps.flood import Flood, FloodResult
from .apps.procs import Proc, spawn, wait_for
from .controller import adjacency, shortest_path
from .naming import Naming

if TYPE_CHECKING:
    from uavcas.twin.model import Attack, Plan, Window

REPLAYER_READY_S = 20.0


class AttackError(RuntimeError):
    """An attack could not be started or stopped; names the attack."""


class AttackExecutor:
    def __init__(self, emu, plan: "Plan", work_dir: Path, duration_s: float,
                 on_event: Callable[[dict], None] | None = None) -> None:
        self.emu, self.plan = emu, plan
        self.work_dir, self.log_dir = work_dir, work_dir / "logs"
        self.duration_s = duration_s
        self.on_event = on_event or (lambda rec: None)
        self.records: list[dict] = []
        self.active: dict[str, "Attack"] = {}
        self.floods: dict[str, list[Flood]] = {}
        self.replayers: dict[str, tuple[Proc, Path]] = {}
        self.window: "Window | None" = None
        self.errors: list[str] = []
        self.inject_records: list[dict] = []

    # helpers -------------------------------------------------------------------------------
    def _ip(self, node: str) -> str:
        return self.plan.node(node).ip

    def _log(self, rec: dict) -> dict:
        self.records.append(rec)
        self.on_event(rec)
        return rec

    def _index(self, node: str) -> int:
        return self.plan.node(node).index

    # lifecycle -----------------------------------------------------------------------------
    def prepare(self) -> None:
        """Before t0: start replay processes (idle until their mirror exists)."""
        for a in self.plan.attacks:
            if a.family == "replay":
                for attacker in a.attackers:
                    self._spawn_replayer(a, attacker)
        for aid, (proc, _) in self.replayers.items():
            if not wait_for(lambda: "ready" in proc.stdout() or not proc.alive(), REPLAYER_READY_S, 0.05) \
                    or not proc.alive():
                raise AttackError(f"{aid}: replayer did not start: {proc.stderr().strip()[-300:]}")

    def _spawn_replayer(self, a: "Attack", attacker: str) -> None:
        p = a.params
        log = self.log_dir / f"inject-{a.attack_id}-{attacker}.jsonl"
        log.parent.mkdir(parents=True, exist_ok=True)
        log.write_text("")
        argv = [sys.executable, "-m", "uavcas.emulation.apps.replayer", "--iface", Naming.HOST_IF,
                "--victim", self._ip(a.victims[0]), "--attacker-ip", self._ip(attacker),
                "--buffer", str(int(p.get("buffer_pkts", 50))), "--delay-ms", str(float(p.get("delay_ms", 200))),
                "--rate-pps", str(float(p.get("rate_pps", 10))), "--ttl-dec", str(int(p.get("ttl_dec", 5))),
                "--seq-mode", str(p.get("seq_mode", "inc")), "--seconds", str(self.duration_s + 30),
                "--seed", str(self.plan.seed * 1000 + self._index(attacker)), "--attack-id", a.attack_id,
                "--log", str(log)]
        proc = spawn(lambda av, t, **kw: self.emu.popen(attacker, av, t, **kw), f"replayer-{a.attack_id}-{attacker}",
                     argv, self.log_dir, self.duration_s + 40)
        self.replayers[f"{a.attack_id}/{attacker}"] = (proc, log)

    def start(self, a: "Attack") -> dict:
        t = time.time()
        extra: dict = {}
        try:
            if a.family in ("dos", "ddos"):
                extra = self._start_flood(a)
            elif a.family == "blackhole":
                extra = self._start_blackhole(a)
            elif a.family == "wormhole":
                self.active[a.attack_id] = a  # wormholes_for() must see it before the FDB is rebuilt
                extra = self._set_wormholes()
            elif a.family == "replay":
                extra = self._start_replay(a)
        except Exception as e:
            raise AttackError(f"{a.attack_id}: start failed: {e}") from e
        self.active[a.attack_id] = a
        return self._log({"event": "start", "attack_id": a.attack_id, "family": a.family,
                          "attackers": list(a.attackers), "attacker_ips": [self._ip(x) for x in a.attackers],
                          "victims": list(a.victims), "victim_ips": [self._ip(v) for v in a.victims],
                          "t_unix": t, "params": dict(a.params), "planned_start_s": a.start_s,
                          "planned_stop_s": a.stop_s, **extra})

    def stop(self, a: "Attack") -> dict:
        if a.attack_id not in self.active:
            return {}
        extra: dict = {}
        try:
            if a.family in ("dos", "ddos"):
                extra = self._stop_flood(a)
            elif a.family == "blackhole":
                extra = {"dropped_frames": hooks.blackhole_off(self.emu.fabric_ns, hooks.blackhole_table(a.attack_id))}
            elif a.family == "wormhole":
                del self.active[a.attack_id]
                extra = self._set_wormholes()
            elif a.family == "replay":
                extra = self._stop_replay(a)
        finally:
            self.active.pop(a.attack_id, None)
        return self._log({"event": "stop", "attack_id": a.attack_id, "family": a.family, "t_unix": time.time(),
                          **extra})

    def stop_all(self) -> None:
        """Stop whatever is still running (end of run, or an interrupt); errors are kept, not raised."""
        for a in list(self.active.values()):
            try:
                self.stop(a)
            except Exception as e:
                self.errors.append(f"{a.attack_id}: stop failed: {e}")
        for proc, _ in self.replayers.values():
            proc.stop(signal.SIGTERM, grace_s=2.0)

    # floods --------------------------------------------------------------------------------
    def _start_flood(self, a: "Attack") -> dict:
        nominal = float(a.params.get("nominal_pps") or 1e6 / float(a.params.get("interval_us", 1000)))
        floods = [Flood(self.emu, a.attack_id, x, self._ip(v), nominal, self.log_dir, self.duration_s + 10)
                  for x in a.attackers for v in a.victims]
        self.floods[a.attack_id] = floods
        for f in floods:
            f.start()
        return {"hping_interval_us": [f.interval_us for f in floods]}

    def calibrate(self, a: "Attack") -> None:
        for f in self.floods.get(a.attack_id, []):
            try:
                f.calibrate()
            except Exception as e:  # the flood keeps running at its first interval
                self.errors.append(f"{a.attack_id}/{f.attacker}: calibration failed: {e}")

    def _stop_flood(self, a: "Attack") -> dict:
        results: list[FloodResult] = [f.stop() for f in self.floods.pop(a.attack_id, [])]
        t = time.time()
        for r in results:
            self._log({"event": "rate", "attack_id": a.attack_id, "family": a.family, "attacker": r.attacker,
                       "measured_pps": round(r.measured_pps, 2), "nominal_pps": r.nominal_pps,
                       "hping_interval_us": r.hping_interval_us, "syn_count": r.syn_count,
                       "seconds": round(r.seconds, 4), "restarts": r.restarts, "intervals_us": r.intervals_us,
                       "victim_ip": r.victim_ip, "t_unix": t})
        return {"syn_count": sum(r.syn_count for r in results)}

    # blackhole -----------------------------------------------------------------------------
    def blackhole_ports(self, victim: str) -> list[str]:
        """The victim switch's host port and (by wildcard) every link port it has or will get."""
        i = self._index(victim)
        return [Naming.host_port(i), Naming.link_port(i, 0).rsplit("-", 1)[0] + "-*"]

    def _start_blackhole(self, a: "Attack") -> dict:
        for v in a.victims:
            hooks.blackhole_on(self.emu.fabric_ns, hooks.blackhole_table(a.attack_id), self.blackhole_ports(v),
                               self._ip(v))
        return {"switch": [self.emu.switch(v).bridge for v in a.victims]}

    # wormhole ------------------------------------------------------------------------------
    def wormholes_for(self, window: "Window") -> list[tuple[str, str, str]]:
        """Overrides to apply with `window` given the wormholes active now (plan's, else derived)."""
        out: list[tuple[str, str, str]] = []
        for a in self.active.values():
            if a.family != "wormhole":
                continue
            for v in a.victims:
                planned = [(o.victim, o.attacker, o.bs) for o in window.wormholes
                           if o.victim == v and o.attacker in a.attackers]
                out += planned or [(v, a.attackers[0], self._bs_of(v))]
        return out

    def routes_for(self, window: "Window") -> list[list[str]]:
        """The window's routes, with the victim's own path while its wormhole is not active.

        The planner routes a victim <-> BS pair through the attacker (and adds the detour's
        links) for every window the wormhole overlaps; the detour must start and stop with the
        attack, not the window. While the attack is idle the pair takes the shortest path that
        avoids the attacker's switch (if there is one; else the plan's route stays).
        """
        idle: dict[tuple[str, str], list[str] | None] = {}
        adj = None
        for a in self.plan.attacks:
            if a.family != "wormhole" or a.attack_id in self.active:
                continue
            if adj is None:
                adj = adjacency([n.name for n in self.plan.nodes], [(lk.a, lk.b) for lk in window.links])
            for v in a.victims:
                b = self._bs_of(v)
                path = shortest_path(adj, v, b, banned=frozenset(a.attackers))
                idle[(v, b)] = path
                idle[(b, v)] = path[::-1] if path else None
        out = []
        for r in window.routes:
            key = (r.src, r.dst)
            out.append(list(idle[key]) if idle.get(key) else list(r.hops))
        return out

    def _bs_of(self, uav: str) -> str:
        uavs = [n.name for n in self.plan.nodes if n.kind == "uav"]
        bss = [n.name for n in self.plan.nodes if n.kind == "bs"]
        return bss[uavs.index(uav) % len(bss)]

    def _set_wormholes(self) -> dict:
        """Re-apply the current window with the active wormholes (routes and overrides together).

        `Emulation.set_wormholes` keeps the routes of the last window apply, which still hold
        the planner's detour after a wormhole stops; re-applying the window recomputes both
        (shaping is unchanged, so only the FDB moves).
        """
        w = self.window
        if w is None:
            raise AttackError("no window applied yet")
        overrides = self.wormholes_for(w)
        rep = self.emu.apply_links(w.links, self.routes_for(w), overrides, window_index=w.index)
        fwd = self.emu.forwarding
        paths = {f"{v}>{b}": fwd.path(v, b) for v, _, b in overrides} if fwd else {}
        return {"fdb_changes": rep.fdb_changes, "paths": paths, "rejected": list(rep.rejected)}

    # replay --------------------------------------------------------------------------------
    def _start_replay(self, a: "Attack") -> dict:
        v = a.victims[0]
        for x in a.attackers:
            proc, _ = self.replayers[f"{a.attack_id}/{x}"]
            if not proc.alive():
                raise AttackError(f"replayer of {x} is not running: {proc.stderr().strip()[-300:]}")
            hooks.mirror_on(self.emu.fabric_ns, self.emu.switch(v).host_port, self.emu.switch(x).host_port)
        return {"mirror": {"from": self.emu.switch(v).host_port,
                           "to": [self.emu.switch(x).host_port for x in a.attackers]}}

    def _stop_replay(self, a: "Attack") -> dict:
        hooks.mirror_off(self.emu.fabric_ns, self.emu.switch(a.victims[0]).host_port)
        stats = {}
        for x in a.attackers:
            proc, _ = self.replayers[f"{a.attack_id}/{x}"]
            proc.stop(signal.SIGTERM, grace_s=3.0)
            for line in proc.stdout().splitlines():
                if line.startswith("{"):
                    stats[x] = json.loads(line).get("stats")
        return {"replayer_stats": stats}

    # the log -------------------------------------------------------------------------------
    def collect(self) -> list[dict]:
        """Read the replayers' inject logs (call before teardown: they live in the run dir)."""
        out = []
        for _, log in self.replayers.values():
            if log.exists():
                out += [json.loads(ln) for ln in log.read_text().splitlines() if ln.strip()]
        self.inject_records = out
        return out

    def log_lines(self) -> list[dict]:
        """Every record, in time order (stable: a stop's rate records stay before the stop)."""
        return sorted(self.records + self.inject_records, key=lambda r: r.get("t_unix", 0.0))
