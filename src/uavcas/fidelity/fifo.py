"""The FIFO model of one link direction: what an ideal emulator would have done with its packets.

A frame that enters switch i at time a (its capture time at point s-i) and leaves towards
switch j on a link the plan gives delay d, rate R and loss p in the window in force at a:

1. **delay**: it becomes ready at r = a + d (a random fraction p never becomes ready: loss is
   drawn before the delay, as the emulator's nft rule runs before its delay stage);
2. **FIFO at the planned rate**: ready frames are served first come, first served (ties in
   capture order) by a token bucket of rate R and depth B bytes, the HTB class the emulator
   installs (`burst` B: what the run logged the kernel held; for runs that did not log it
   `HTB_BURST_BYTES`, tc's default on a high-resolution-timer kernel: one MTU, so a backlogged
   class the host froze catches up only one frame's worth). A frame may start when the bucket is not in debt and
   the frame before it has started; starting charges its length L (Ethernet frame bytes, the
   captured `frame_len`), and the bucket refills at R up to B:

       start_k = max(r_k, start_{k-1}, Z_{k-1})
       Z_k     = max(Z_{k-1}, start_k - 8 B(start_k) / R(start_k)) + 8 L_k / R(start_k)   (Z: debt paid)

   R(t) and B(t) are the rate and depth *in force at t*: a window change rewrites the HTB class in place, the
   frames already queued stay and HTB charges each one at dequeue with the class's rate then
   (`htb_charge_class`), while a debt already run up is kept in time units (HTB's tokens are
   nanoseconds), so Z carries over a change unscaled;
3. it is captured at switch j at `start_k` (a veth hands a frame over as it is sent).

Its **delay error** is `t_j - start_k` (measured capture time at j minus the model's): positive
when the emulator was late. Frames the emulator lost on the hop are not served by the model:
a random loss never reached the queue, and a tail drop never entered it (the queue was full),
so neither delays the frames behind it. `backlog(t)` counts the frames the model holds (ready,
not started) at time t: the pfifo's length, which `losses` uses to tell a queue-tail drop
(backlog at the queue limit) from a random one. A frame's model is driven by its *measured* arrival at i, so an error
is the hop's own and never accumulates along a path.
"""

from __future__ import annotations

import bisect
import math
from dataclasses import dataclass

import numpy as np

HTB_BURST_BYTES = 1600  # tc's default HTB burst where /proc/net/psched reports a 1 GHz clock


CHANGE_HORIZON_S = 0.5  # how long after an apply ends the candidate change times are compared


def serve(ready_s: np.ndarray, length_b: np.ndarray, rate_t_s: np.ndarray, rate_mbps: np.ndarray,
          burst_b: float | np.ndarray = HTB_BURST_BYTES, rate_until_s: np.ndarray | None = None,
          seen_s: np.ndarray | None = None) -> np.ndarray:
    """Model start times of frames (already sorted by ready time) on one link direction.

    The rate is piecewise constant: `rate_mbps[k]` from `rate_t_s[k]` on (ascending; the first
    rate also before `rate_t_s[0]`), and so is the bucket's depth `burst_b` (one value for every
    setting, or one per setting). Each frame is charged at the setting in force when it starts.

    Where a change is only known to have happened somewhere in `[rate_t_s[k], rate_until_s[k])`
    (a window's apply rewrites every port in one batch and logs when the batch began and ended,
    not when it reached this port), every frame boundary inside that interval is a candidate for
    the change: the model keeps the one whose start times match the frames' measured starts
    `seen_s` best up to `CHANGE_HORIZON_S` after the interval (a frame charged at the wrong rate
    leaves the bucket off by the difference, which shows as soon as a frame waits for it). This is
    the only use of measured times in the model.
    """
    n = ready_s.shape[0]
    if n == 0:
        return np.empty(0, dtype=np.float64)
    # Times relative to the first frame: Unix seconds as float64 are only good to 0.24 us, and
    # the recursion adds costs up over thousands of back-to-back frames (a 54-byte frame's cost
    # rounded to 0.24 us drifted the model by 0.1 us per frame, 0.6 ms over a 5 s flood).
    base = float(ready_s[0])
    change = np.asarray(rate_t_s, dtype=np.float64) - base
    until = change if rate_until_s is None else np.asarray(rate_until_s, dtype=np.float64) - base
    burst = np.broadcast_to(np.asarray(burst_b, dtype=np.float64) * 8.0, np.shape(rate_mbps))
    q = _Queue(ready=(ready_s - base).tolist(), bits=(np.asarray(length_b, dtype=np.float64) * 8.0).tolist(),
               bits_per_s=(np.asarray(rate_mbps, dtype=np.float64) * 1e6).tolist(),
               change=change.tolist() + [math.inf], until=until.tolist() + [math.inf], burst=burst.tolist(),
               seen=None if seen_s is None else (np.asarray(seen_s, dtype=np.float64) - base).tolist())
    return np.array(q.serve(), dtype=np.float64) + base


@dataclass
class _Queue:
    """The recursion of the module docstring over one direction's frames (times from the first)."""

    ready: list[float]
    bits: list[float]
    bits_per_s: list[float]  # per rate setting
    change: list[float]  # setting k holds from change[k] (inf-terminated) ...
    until: list[float]  # ... at the latest from until[k]
    burst: list[float]  # bucket depth (bits) per setting
    seen: list[float] | None

    def serve(self) -> list[float]:
        n, ready, change = len(self.ready), self.ready, self.change
        out = [0.0] * n
        prev = debt = -math.inf
        k = m = 0
        while m < n:
            s = max(ready[m], prev, debt)
            if change[k + 1] <= s:  # start times never decrease: the setting only moves on
                if self.seen is not None and s < self.until[k + 1]:
                    m, prev, debt = self._resolve(m, prev, debt, k, out)
                k += 1
                continue
            debt = self._charge(debt, s, self.bits[m], self.bits_per_s[k], self.burst[k])
            out[m] = prev = s
            m += 1
        return out

    def _charge(self, debt: float, s: float, bits: float, bits_per_s: float, burst: float) -> float:
        """When the bucket's debt is paid after a frame of `bits` starts at s (HTB: tokens capped
        at one burst, then the frame's cost at the class rate)."""
        floor = s - burst / bits_per_s
        return (debt if debt > floor else floor) + bits / bits_per_s

    def _resolve(self, m: int, prev: float, debt: float, k: int, out: list[float]) -> tuple[int, float, float]:
        """Frame m starts inside change k+1's interval: the change came before frame m, m+1, ...
        (a frame still charged at the old rate must start before the interval ends); fill in the
        frames up to the horizon with the candidate that best matches their measured starts."""
        horizon = min(self.until[k + 1] + CHANGE_HORIZON_S, self.change[k + 2])
        end = max(bisect.bisect_left(self.ready, horizon, lo=m), m + 1)
        best = None
        for h in range(end - m + 1):
            run = self._run(m, end, prev, debt, k, h)
            if run is None:
                break  # frame m + h - 1 would start after the change had surely happened
            if best is None or run[0] < best[0]:
                best = run
        _, starts, prev, debt = best
        out[m:end] = starts
        return end, prev, debt

    def _run(self, m: int, end: int, prev: float, debt: float, k: int,
             h: int) -> tuple[float, list[float], float, float] | None:
        """Frames m..end-1 with the first h of them at setting k and the rest at k+1: (sum of
        |start - seen|, starts, last start, debt), or None when that cannot be."""
        old, new, until = self.bits_per_s[k], self.bits_per_s[k + 1], self.until[k + 1]
        burst_old, burst_new = self.burst[k], self.burst[k + 1]
        starts, cost = [], 0.0
        for x in range(m, end):
            s = max(self.ready[x], prev, debt)
            if x - m < h and s >= until:
                return None
            debt = self._charge(debt, s, self.bits[x], *((old, burst_old) if x - m < h else (new, burst_new)))
            starts.append(s)
            prev = s
            cost += abs(s - self.seen[x])
        return cost, starts, prev, debt


def backlog(ready_s: np.ndarray, start_s: np.ndarray, t_s: np.ndarray) -> np.ndarray:
    """Frames the model holds (ready at or before t, started after t) at each time t."""
    return (np.searchsorted(ready_s, t_s, side="right") - np.searchsorted(start_s, t_s, side="right")).astype(np.int64)


def busy_intervals(ready_s: np.ndarray, start_s: np.ndarray) -> np.ndarray:
    """Merged [begin, end) intervals in which the model held at least one frame waiting."""
    wait = start_s > ready_s
    if not wait.any():
        return np.zeros((0, 2))
    b, e = ready_s[wait], start_s[wait]
    # FIFO: both sorted; an interval joins the previous one when it begins before that one ends
    run_end = np.maximum.accumulate(e)
    new = np.ones(b.shape[0], dtype=bool)
    new[1:] = b[1:] >= run_end[:-1]
    idx = np.flatnonzero(new)
    ends = np.append(run_end[idx[1:] - 1], run_end[-1])
    return np.stack([b[idx], ends], axis=1)
