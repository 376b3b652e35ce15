"""hping3 SYN flood paced from outside: one process per attacker, exact rate, exact window.

`hping3 -i uN` re-arms its interval timer in its own SIGALRM handler, so its real period is N
plus the handler's latency, which grows with the load on the cores: a closed loop restarting
hping3 with corrected intervals ran away on a late schedule (1,000 -> 2,500 pps) and every
restart reused source ports (one "flow" spanning separate bursts). Instead:

* hping3 is started once per attacker *before* t0 (`prepare`), with `-i 3600`: it never sends
  on its own. A pacer (`pacer.py`, one process per hping3) sends it
  SIGALRM at absolute deadlines t_go + k / pps: each signal is one SYN. A standard signal does
  not queue, so the pacer signals only when the previous one was consumed (the pidfd's
  process no longer has SIGALRM pending) and catches up after a late wake-up, never faster
  than `PACE_FLOOR_US` apart: the rate is the nominal one whatever the lateness, and the
  floor bounds it (a nominal interval below the floor is paced at the floor, and logged so).
* hping3 sends one SYN as soon as it starts. Until the attack starts a gate in the attacker's
  namespace steers its SYNs to the victim into a veth pair that leads nowhere (an nft `route`
  chain marks them, an `ip rule` routes the mark to that veth): nothing reaches a switch, and
  the first gated SYN tells us hping3 is ready. `start_all` opens the gates, notes the time,
  then lets the pacers go: every SYN leaves after the logged start.
* `close_all` stops the pacers, closes the gates (a SYN still pending in hping3 is gated) and
  signals hping3; `collect_all` then waits for hping3 and reads the exact count of SYNs that
  left `eth0` (nft counter on postrouting), off the schedule's thread. The
  attack's stop time is the gate's closing; the time by which the last SYN can have crossed the
  network (logged as `crossed_unix`) adds, on the attacker -> victim path, each hop's planned
  delay and the sojourn of a full queue (`quiet_after_s`).
"""

from __future__ import annotations

import json
import os
import re
import signal
import subprocess
import sys
import time
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

from uavcas.emulation.apps.procs import Proc, spawn, wait_for
from uavcas.network.queues import full_queue_s

from . import tool_path
from .pacer import PACE_FLOOR_US, PRIORITY_NICE

HPING_IDLE_S = 3600  # hping3's own interval: longer than any run, so only the pacer makes it send
READY_TIMEOUT_S = 10.0
QUIET_SLACK_S = 0.02  # on top of the path bound: the delay stage's wake-up lateness
_gate_ids = iter(range(1, 10_000))  # per process: gate devices, marks and route tables are unique


def pace_interval_us(nominal_pps: float) -> int:
    return max(PACE_FLOOR_US, round(1e6 / nominal_pps))


def table_name(attack_id: str) -> str:
    return "uavcas_f_" + re.sub(r"[^A-Za-z0-9_]", "_", attack_id)


def _match(victim_ip: str, port: int) -> str:
    return f"ip daddr {victim_ip} tcp dport {port} tcp flags & (syn | ack) == syn"


def counter_ruleset(table: str, victim_ip: str, port: int, out_if: str = "eth0") -> str:
    """Counters `syn` (SYNs that left `out_if`) and `gated`, and the empty `gate` route chain."""
    return (f"table ip {table} {{\n"
            f"  counter syn {{ }}\n  counter gated {{ }}\n"
            f"  chain gate {{ type route hook output priority mangle; policy accept; }}\n"
            f"  chain post {{ type filter hook postrouting priority 0; policy accept;\n"
            f"    oifname \"{out_if}\" {_match(victim_ip, port)} counter name syn\n"
            f"  }}\n}}\n")


def gate_rule(table: str, victim_ip: str, port: int, mark: int) -> str:
    return f"add rule ip {table} gate {_match(victim_ip, port)} counter name gated meta mark set {mark:#x}\n"


def gate_lines(gid: int, mark: int, route_table: int) -> list[str]:
    """`ip -batch` lines (attacker's namespace): the veth pair a gated SYN is routed into. Its
    peer has no address and the frame is not for its MAC (ARP off): dropped in silence, and
    hping3's sendto succeeds (a blackhole route would fail it, and hping3 exits on that)."""
    a, b = f"fg{gid}a", f"fg{gid}b"
    return [f"link add {a} type veth peer name {b}", f"link set {a} arp off up", f"link set {b} up",
            f"rule add fwmark {mark:#x} table {route_table}", f"route add default dev {a} table {route_table}"]


def parse_counters(nft_json: str) -> dict[str, int]:
    out = {}
    for item in json.loads(nft_json).get("nftables", []):
        if "counter" in item:
            out[item["counter"]["name"]] = int(item["counter"]["packets"])
    return out


def quiet_after_s(hops: Sequence[tuple[float, float]]) -> float:
    """Longest time a packet can spend on a path of (delay_ms, rate_mbps) hops: each hop's delay
    plus a full queue drained at its rate (`network.queues.full_queue_s`)."""
    return QUIET_SLACK_S + sum(d / 1000 + full_queue_s(r) for d, r in hops)


@dataclass
class FloodResult:
    attacker: str
    victim_ip: str
    nominal_pps: float
    interval_us: int  # the pacing interval (nominal, or the floor)
    syn_count: int  # SYNs that left the attacker (nft counter)
    signals: int  # SIGALRMs the pacer delivered
    seconds: float  # from the pacer's go to its stop
    max_behind: int  # most SYNs the pacer was ever behind its deadlines

    @property
    def measured_pps(self) -> float:
        return self.syn_count / self.seconds if self.seconds > 0 else 0.0


class Flood:
    """One attacker's SYN flood on a running Emulation (see the module docstring). `start_all`,
    `close_all` and `collect_all` act on all of an attack's floods at once (their kernel calls concurrent)."""

    def __init__(self, emu, attack_id: str, attacker: str, victim_ip: str, nominal_pps: float,
                 log_dir: Path, max_s: float, port: int = 80) -> None:
        self.emu, self.attacker, self.victim_ip, self.port = emu, attacker, victim_ip, port
        self.nominal_pps = float(nominal_pps)
        self.interval_us = pace_interval_us(self.nominal_pps)
        self.table = table_name(attack_id)
        self.log_dir, self.max_s = log_dir, max_s
        self.gid = next(_gate_ids)
        self.mark, self.route_table = 0x5CA10000 + self.gid, 20000 + self.gid
        self.hping: Proc | None = None
        self.pacer: Proc | None = None

    # kernel calls, as (node, argv, stdin) jobs for `_run_all` --------------------------------------
    def _nft_job(self, *args: str, text: str | None = None) -> tuple[str, list[str], str | None]:
        return self.attacker, ["nft", *args], text

    def open_gate_job(self):
        return self._nft_job("flush", "chain", "ip", self.table, "gate")

    def close_gate_job(self):
        return self._nft_job("-f", "-", text=gate_rule(self.table, self.victim_ip, self.port, self.mark))

    def counters_job(self):
        return self._nft_job("-j", "list", "counters", "table", "ip", self.table)

    def remove_job(self):
        return self._nft_job("delete", "table", "ip", self.table)

    def counters(self) -> dict[str, int]:
        return parse_counters(_run_all(self.emu, [self.counters_job()])[0])

    # lifecycle -------------------------------------------------------------------------------
    def prepare(self) -> list[Proc]:
        """Before t0: gate closed, hping3 started and seen ready, pacer waiting. Returns both
        processes (the executor stops them whatever happens)."""
        _run_all(self.emu, [(self.attacker, ["ip", "-batch", "-"],
                             "\n".join(gate_lines(self.gid, self.mark, self.route_table)) + "\n")])
        _run_all(self.emu, [self._nft_job("-f", "-", text=counter_ruleset(self.table, self.victim_ip, self.port)
                                          + gate_rule(self.table, self.victim_ip, self.port, self.mark))])
        argv = ["hping3", "-S", "-p", str(self.port), "-i", str(HPING_IDLE_S), "-q", self.victim_ip]
        name = f"hping3-{self.table}-{self.attacker}"
        self.hping = spawn(lambda a, t, **kw: self.emu.popen(self.attacker, a, t, **kw), name, argv, self.log_dir,
                           self.max_s)
        if not wait_for(lambda: not self.hping.alive() or self.counters().get("gated", 0) >= 1, READY_TIMEOUT_S,
                        0.02) or not self.hping.alive():
            raise RuntimeError(f"hping3 in {self.attacker} did not start: {self.hping.stderr()[-300:].strip()}")
        pid = _only_child(self.hping.pid)
        # Each SYN is one wake-up of hping3, and the next signal waits for it: on busy cores a
        # nice-0 hping3 woke too late to keep 1,000/s (865/s beside 5 CPU hogs). It needs
        # little CPU, so a higher priority costs the other tools almost nothing.
        os.setpriority(os.PRIO_PROCESS, pid, PRIORITY_NICE)
        err_path = self.log_dir / f"pacer-{self.table}-{self.attacker}.err"
        with open(err_path, "wb") as err:
            # --ns only names the run (`ps` shows whose pacer it is); it exits with its runner
            # (stdin EOF) or its hping3 (pidfd)
            pacer = subprocess.Popen([sys.executable, str(tool_path("pacer")), "--pid", str(pid),
                                      "--pps", str(1e6 / self.interval_us), "--ns", self.emu.ns(self.attacker)],
                                     stdin=subprocess.PIPE,
                                     stdout=subprocess.PIPE, stderr=err, start_new_session=True)
        self.pacer = Proc(f"pacer-{self.attacker}", pacer, Path(os.devnull), err_path)
        if pacer.stdout.readline().strip() != b"ready":
            raise RuntimeError(f"flood pacer for {self.attacker} did not start: {self.pacer.stderr()[-300:]}")
        return [self.hping, self.pacer]

    def _tell(self, word: bytes) -> None:
        try:
            self.pacer.popen.stdin.write(word + b"\n")
            self.pacer.popen.stdin.flush()
        except BrokenPipeError:  # it already stopped: hping3 exited (its report says so)
            pass

    def _report(self) -> dict:
        try:
            out, _ = self.pacer.popen.communicate(timeout=10)
            return json.loads(out.decode().strip().splitlines()[-1])
        except (ValueError, IndexError, subprocess.TimeoutExpired) as e:
            raise RuntimeError(f"flood pacer for {self.attacker} gave no report: {e}; "
                               f"{self.pacer.stderr()[-300:]}") from None


def start_all(floods: Sequence[Flood]) -> float:
    """Open every gate, then let every pacer go; returns the time from which SYNs can go."""
    if floods:
        _run_all(floods[0].emu, [f.open_gate_job() for f in floods])
    t = time.time()
    for f in floods:
        f._tell(b"go")
    return t


def close_all(floods: Sequence[Flood]) -> float:
    """Pacers stopped, gates closed (a SYN still pending in hping3 is gated), hping3 told to stop:
    the time-critical half of a stop. Returns the time the gates were closed (no SYN leaves an
    attacker after it)."""
    if not floods:
        return time.time()
    for f in floods:
        f._tell(b"stop")
    try:
        _run_all(floods[0].emu, [f.close_gate_job() for f in floods])
    finally:
        t_closed = time.time()
        for f in floods:  # all at once; waited for by `collect_all`
            if f.hping.alive():
                f.hping.popen.send_signal(signal.SIGINT)
    return t_closed


def collect_all(floods: Sequence[Flood]) -> list[FloodResult]:
    """The rest of a stop after `close_all`: pacer reports and counts read, hping3 waited for,
    tables removed. Raises only after every step ran for every flood."""
    if not floods:
        return []
    emu = floods[0].emu
    reports, errors = [], []
    for f in floods:
        try:
            reports.append(f._report())
        except RuntimeError as e:
            errors.append(str(e))
    try:
        counts = [parse_counters(out).get("syn", 0) for out in _run_all(emu, [f.counters_job() for f in floods])]
    finally:
        for f in floods:
            f.hping.stop(signal.SIGINT, grace_s=2.0)
        # the table (its closed gate would catch a later flood's SYNs); the gate's veth and
        # rule match nothing without it and go with the namespace
        _run_all(emu, [f.remove_job() for f in floods])
    if errors:
        raise RuntimeError("; ".join(errors))
    return [FloodResult(f.attacker, f.victim_ip, f.nominal_pps, f.interval_us, n, r["signals"], r["seconds"],
                        r["max_behind"]) for f, n, r in zip(floods, counts, reports)]


def _run_all(emu, jobs: list[tuple[str, list[str], str | None]], timeout_s: float = 15.0) -> list[str]:
    """Run (node, argv, stdin) jobs in their nodes' namespaces concurrently; their stdouts."""
    procs = [subprocess.Popen(emu.hosts.argv(node, argv, timeout_s), stdin=subprocess.PIPE, stdout=subprocess.PIPE,
                              stderr=subprocess.PIPE, text=True) for node, argv, _ in jobs]
    outs, errors = [], []
    for (node, argv, text), p in zip(jobs, procs):
        out, err = p.communicate(text, timeout=timeout_s + 5)
        if p.returncode != 0:
            errors.append(f"{' '.join(argv[:4])} in {node}: {err.strip()[:300]}")
        outs.append(out)
    if errors:
        raise RuntimeError("; ".join(errors))
    return outs


def _only_child(pid: int, timeout_s: float = 5.0) -> int:
    """The tool under our `timeout` wrapper (`ip netns exec` execs it: one child)."""
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        try:
            kids = Path(f"/proc/{pid}/task/{pid}/children").read_text().split()
        except OSError:
            kids = []
        if kids:
            return int(kids[0])
        time.sleep(0.01)
    raise RuntimeError(f"no child process under {pid}")


# the pacer (own process) -----------------------------------------------------------------------
