"""How contended are this machine's CPUs right now? (for `uavcas doctor` and run diagnostics)

Timing fidelity of an emulation on few cores depends on whether the delay stage, the tools
and the kernel's softirqs get a CPU when they need one. `ContentionProbe` measures that over an
interval, from three independent sources:

* CPU pressure (PSI, `/proc/pressure/cpu`, Linux >= 4.20): the share of wall time in which at
  least one runnable task waited for a CPU ("some");
* the run queue: runnable tasks per CPU, sampled from `/proc/stat` `procs_running`, and the
  hypervisor's steal time from the `cpu` line;
* a timer probe: a process waiting `TIMER_PERIOD_S` at a time records how late it wakes up.
  This is what a nice-0 tool in a namespace (curl, nginx, hping3) sees, and what PSI cannot
  tell on its own (pressure with short waits is harmless).

`level` is "quiet", "contended" (warn: timing figures of runs made now are less faithful) or
"saturated" (fail: the emulator cannot keep its timing here). Thresholds are documented
constants; they were chosen from measurements on the 2-core development machine (quiet, one and
two CPU-bound processes, `stress-ng --cpu 4`; docs/architecture.md, "doctor").
"""

from __future__ import annotations

import json
import os
import select
import subprocess
import sys
import time
from dataclasses import asdict, dataclass
from pathlib import Path

from .selftest import percentile

PSI_CPU = Path("/proc/pressure/cpu")
PROC_STAT = Path("/proc/stat")
TIMER_PERIOD_S = 0.002
SAMPLE_EVERY_S = 0.05

# "contended" when any of these is exceeded, "saturated" when the timer probe's p99 lateness
# exceeds SATURATED_TIMER_P99_US, the run queue holds more than SATURATED_RUNQ_PER_CPU runnable
# tasks per CPU on average (each task then gets at most 1/that of a CPU), or some task waited
# for a CPU more than SATURATED_PSI_SOME_PCT of the time. Measured here: one CPU hog gives
# pressure 15-36 %, 1.2-1.5 runnable per CPU, p99 lateness 0.8-3.9 ms; two hogs 62-81 %, 1.9-2.6,
# 1.8-6 ms; `stress-ng --cpu 4` 77-98 %, 2.5-11, 0.2-10 ms (every signal alone can miss it).
CONTENDED_PSI_SOME_PCT = 40.0
CONTENDED_TIMER_P99_US = 1000.0
CONTENDED_RUNQ_PER_CPU = 1.0
CONTENDED_STEAL_PCT = 10.0
SATURATED_TIMER_P99_US = 4000.0
SATURATED_RUNQ_PER_CPU = 2.0
SATURATED_PSI_SOME_PCT = 75.0


@dataclass(frozen=True)
class Contention:
    seconds: float
    cpus: int
    psi_some_pct: float | None  # None: no PSI on this kernel
    runq_per_cpu: float  # mean runnable tasks per CPU (this probe's own thread excluded)
    steal_pct: float
    timer_late_p50_us: float
    timer_late_p99_us: float
    timer_wakeups: int

    @property
    def reasons(self) -> list[str]:
        """What makes the machine contended (empty when quiet)."""
        out = []
        if self.psi_some_pct is not None and self.psi_some_pct > CONTENDED_PSI_SOME_PCT:
            out.append(f"CPU pressure {self.psi_some_pct:.0f} % of the time (> {CONTENDED_PSI_SOME_PCT:g})")
        if self.runq_per_cpu > CONTENDED_RUNQ_PER_CPU:
            out.append(f"{self.runq_per_cpu:.1f} runnable tasks per CPU (> {CONTENDED_RUNQ_PER_CPU:g})")
        if self.steal_pct > CONTENDED_STEAL_PCT:
            out.append(f"steal {self.steal_pct:.0f} % (> {CONTENDED_STEAL_PCT:g})")
        if self.timer_late_p99_us > CONTENDED_TIMER_P99_US:
            out.append(f"timer wake-ups {self.timer_late_p99_us / 1000:.1f} ms late at p99 "
                       f"(> {CONTENDED_TIMER_P99_US / 1000:g})")
        return out

    @property
    def level(self) -> str:
        if (self.timer_late_p99_us > SATURATED_TIMER_P99_US or self.runq_per_cpu > SATURATED_RUNQ_PER_CPU
                or (self.psi_some_pct or 0.0) > SATURATED_PSI_SOME_PCT):
            return "saturated"
        return "contended" if self.reasons else "quiet"

    def to_dict(self) -> dict:
        return {**asdict(self), "level": self.level, "reasons": self.reasons}


def _psi_some_total_us() -> int | None:
    try:
        for line in PSI_CPU.read_text().splitlines():
            if line.startswith("some"):
                return int(dict(kv.split("=") for kv in line.split()[1:])["total"])
    except (OSError, KeyError, ValueError):
        return None
    return None


def _cpu_line() -> tuple[int, int]:
    """(total jiffies, steal jiffies) of the aggregate `cpu` line of /proc/stat."""
    fields = PROC_STAT.read_text().split("\n", 1)[0].split()[1:]
    vals = [int(x) for x in fields[:8]]
    return sum(vals), vals[7] if len(vals) > 7 else 0


def _procs_running() -> int:
    for line in PROC_STAT.read_text().splitlines():
        if line.startswith("procs_running"):
            return int(line.split()[1])
    return 0


def _sample_until_eof(stream) -> dict:
    """The timer probe: wait TIMER_PERIOD_S at a time for `stream` to close, recording how late
    each wait returns, and the run queue every SAMPLE_EVERY_S. Runs in a process of its own: in
    the caller's, its wake-ups would wait for the interpreter lock as well."""
    late_us: list[float] = []
    runq: list[int] = []
    next_sample = time.monotonic()
    while True:
        t = time.monotonic()
        ready, _, _ = select.select([stream], [], [], TIMER_PERIOD_S)
        woke = time.monotonic()
        if ready:
            break
        late_us.append(max(0.0, (woke - t - TIMER_PERIOD_S) * 1e6))
        if woke >= next_sample:
            runq.append(max(0, _procs_running() - 1))  # this process is running while it reads
            next_sample = woke + SAMPLE_EVERY_S
    late = sorted(late_us or [0.0])
    return {"late_p50_us": percentile(late, 50), "late_p99_us": percentile(late, 99),
            "wakeups": len(late_us), "runq": sum(runq) / len(runq) if runq else 0.0}


class ContentionProbe:
    """Measure contention while a block runs: `with ContentionProbe() as probe: ...; probe.result`."""

    def __init__(self) -> None:
        self.cpus = len(os.sched_getaffinity(0))
        self.result: Contention | None = None
        self._proc: subprocess.Popen | None = None

    def __enter__(self) -> "ContentionProbe":
        self._proc = subprocess.Popen([sys.executable, "-m", "uavcas.diagnostics.contention"], stdin=subprocess.PIPE,
                                      stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True,
                                      start_new_session=True)
        self._t0 = time.monotonic()
        self._psi0 = _psi_some_total_us()
        self._cpu0 = _cpu_line()
        return self

    def __exit__(self, *exc: object) -> None:
        secs = time.monotonic() - self._t0
        psi1, cpu1 = _psi_some_total_us(), _cpu_line()
        try:
            out, _ = self._proc.communicate("", timeout=10)  # closing stdin ends the probe
            probe = json.loads(out)
        except (subprocess.TimeoutExpired, ValueError):
            self._proc.kill()
            self._proc.wait()
            return  # no result: the caller reports the contention as unknown
        psi = None if self._psi0 is None or psi1 is None else 100.0 * (psi1 - self._psi0) / 1e6 / secs
        total, steal = cpu1[0] - self._cpu0[0], cpu1[1] - self._cpu0[1]
        self.result = Contention(
            seconds=round(secs, 3), cpus=self.cpus, psi_some_pct=None if psi is None else round(min(100.0, psi), 1),
            runq_per_cpu=round(probe["runq"] / self.cpus, 2),
            steal_pct=round(100.0 * steal / total, 1) if total > 0 else 0.0,
            timer_late_p50_us=round(probe["late_p50_us"], 1), timer_late_p99_us=round(probe["late_p99_us"], 1),
            timer_wakeups=probe["wakeups"])


def measure(seconds: float = 1.0) -> Contention | None:
    """Contention over the next `seconds` (the caller only waits)."""
    with ContentionProbe() as p:
        time.sleep(seconds)
    return p.result


if __name__ == "__main__":
    print(json.dumps(_sample_until_eof(sys.stdin)), flush=True)
