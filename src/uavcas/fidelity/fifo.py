"""The FIFO model of one link direction: what an ideal emulator would have done with its packets.

A frame that enters switch i at time a (its capture time at point s-i) and leaves towards
switch j on a link the plan gives delay d, rate R and loss p in the window in force at a:

1. **delay**: it becomes ready at r = a + d (a random fraction p never becomes ready: loss is
   drawn before the delay, as the emulator's nft rule runs before its delay stage);
2. **FIFO at the planned rate**: ready frames are served first come, first served (ties in
   capture order) by a token bucket of rate R and depth B bytes, the HTB class the emulator
   installs (`burst` B, default `HTB_BURST_BYTES`, tc's default on a high-resolution-timer
   kernel: one MTU). A frame may start when the bucket is not in debt and the frame before it
   has started; starting charges its length L (Ethernet frame bytes, the captured `frame_len`),
   and the bucket refills at R up to B:

       start_k = max(r_k, start_{k-1}, Z_{k-1})
       Z_k     = max(Z_{k-1}, start_k - 8 B / R) + 8 L_k / R      (Z: when the debt is paid)

3. it is captured at switch j at `start_k` (a veth hands a frame over as it is sent).

Its **delay error** is `t_j - start_k` (measured capture time at j minus the model's): positive
when the emulator was late. Frames the emulator lost on the hop are not served by the model;
`backlog(t)` counts the frames the model holds (ready, not started) at time t, which tells a
queue-tail drop (backlog at the queue limit) from a random one. A frame's model is driven by its
*measured* arrival at i, so an error is the hop's own and never accumulates along a path.
"""

from __future__ import annotations

import numpy as np

HTB_BURST_BYTES = 1600  # tc's default HTB burst where /proc/net/psched reports a 1 GHz clock


def serve(ready_s: np.ndarray, length_b: np.ndarray, rate_mbps: np.ndarray,
          burst_b: float = HTB_BURST_BYTES) -> np.ndarray:
    """Model start times of frames (already sorted by ready time) on one link direction.

    `rate_mbps` per frame: the rate in force when it became ready (windows change it).
    """
    n = ready_s.shape[0]
    start = np.empty(n, dtype=np.float64)
    if n == 0:
        return start
    cost = (length_b.astype(np.float64) * 8.0 / (rate_mbps.astype(np.float64) * 1e6)).tolist()
    depth = (burst_b * 8.0 / (rate_mbps.astype(np.float64) * 1e6)).tolist()
    ready = ready_s.tolist()
    prev, debt = -np.inf, -np.inf
    out = [0.0] * n
    for k in range(n):
        s = ready[k]
        if prev > s:
            s = prev
        if debt > s:
            s = debt
        floor = s - depth[k]
        debt = (debt if debt > floor else floor) + cost[k]
        out[k] = prev = s
    start[:] = out
    return start


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
