"""What each window applied, and what the kernel counted in it, read off the schedule's path.

A window change must be quick (issue #14: <= 250 ms at 100 UAVs); reading back every port's
rate, loss and delay took up to 1 s more under load. `WindowSampler` does it in a background
thread after each change (at real-time priority just below the change itself, see `_work`), together with a snapshot of
every port's kernel counters (`Shaper.counters`). A window's counters are the difference between the snapshot taken
right after it was applied and the next one (the next window's change, or `end()` at the end of
the schedule), so each lands in that window's shaping.jsonl records. A reshape inside a window (an attack's
shaping: `AttackExecutor.reshape`) is sampled the same way as a new segment of the window
(`ShapingRecord.segment`), so each setting's counters are its own.
"""

from __future__ import annotations

import queue
import threading
from collections.abc import Sequence
from dataclasses import dataclass, replace

from .priority import CONTROL_RT_PRIORITY, urgent
from .shaping import PortCounters, Shape, Shaper, ShapingRecord

SNAPSHOT_RT_PRIORITY = CONTROL_RT_PRIORITY - 1  # just below the window change itself


@dataclass
class _Sample:
    window: int
    shapes: list[Shape]
    records: list[ShapingRecord]
    counters: dict[str, PortCounters]


class WindowSampler:
    def __init__(self, shaper: Shaper, readback: bool = True) -> None:
        self.shaper, self.readback = shaper, readback
        self.samples: list[_Sample] = []
        self.final: dict[str, PortCounters] | None = None
        self.errors: list[str] = []
        self._ports: set[str] = set()  # every port of every window so far
        self._last: int | None = None  # window of the last apply, and its segment
        self._segment = 0
        self._jobs: queue.Queue = queue.Queue()
        self._thread = threading.Thread(target=self._work, name="window-sampler", daemon=True)
        self._thread.start()

    def window_applied(self, window: int, shapes: Sequence[Shape]) -> None:
        """A window was applied, or (the same window again) re-shaped within it: a new segment."""
        self._segment = self._segment + 1 if window == self._last else 0
        self._last = window
        self._jobs.put(((window, self._segment), list(shapes)))

    def end(self) -> None:
        """The schedule is over: the last window's counters end here."""
        self._jobs.put(("end", None))

    def _work(self) -> None:
        while True:
            job, shapes = self._jobs.get()
            if job is None:
                return
            window, segment = job if isinstance(job, tuple) else (job, 0)
            try:
                if window == "end":
                    with urgent(SNAPSHOT_RT_PRIORITY):
                        self.final = self.shaper.counters(sorted(self._ports))
                    continue
                ports = [s.port for s in shapes]
                self._ports.update(ports)  # the previous window's ports end here too
                # Promptly: the snapshot marks the window's edge. And the read-back too: its dumps
                # hold the kernel's RTNL lock, which a window change waits for; at normal priority
                # on a loaded machine they held it for hundreds of ms (priority inversion).
                with urgent(SNAPSHOT_RT_PRIORITY):
                    counters = self.shaper.counters(sorted(self._ports))
                    records = self.shaper.records(window, shapes, self.shaper.readback(ports)) if self.readback else []
                records = [replace(r, segment=segment) for r in records]
                self.samples.append(_Sample(window, shapes, records, counters))
            except Exception as e:  # a failed read must not end the run: it is reported
                self.errors.append(f"window {window}: {type(e).__name__}: {e}")

    def close(self, timeout_s: float = 30.0) -> list[ShapingRecord]:
        """Wait for pending reads; the records of every window, counters filled where known."""
        self._jobs.put((None, None))
        self._thread.join(timeout_s)
        if self._thread.is_alive():
            self.errors.append(f"window sampler still busy after {timeout_s} s")
        out = []
        for k, smp in enumerate(self.samples):
            after = self.samples[k + 1].counters if k + 1 < len(self.samples) else self.final
            for rec in smp.records:
                out.append(_with_counters(rec, smp.counters.get(rec.port), (after or {}).get(rec.port)))
        return out


def _with_counters(rec: ShapingRecord, before: PortCounters | None, after: PortCounters | None) -> ShapingRecord:
    if before is None or after is None:
        return rec

    def delta(a: int | None, b: int | None) -> int | None:
        return None if a is None or b is None or b < a else b - a

    return replace(rec, sent_packets=delta(before.sent_packets, after.sent_packets),
                   queue_drops=delta(before.queue_drops, after.queue_drops),
                   loss_drops=delta(before.loss_drops, after.loss_drops),
                   link_drops=delta(before.link_drops, after.link_drops),
                   paced_packets=delta(before.paced_packets, after.paced_packets))
