"""A port's pacing in the delay stage: the token-bucket FIFO of the fidelity audit, in virtual time.

The delay stage (`nfqdelay`: the compiled loop `nfqdelay.c`, or the Python loop that uses this
module) serves a paced port's frames first come, first served through a bucket of rate R and
depth B, from the frames' kernel receive stamps, exactly as `uavcas.fidelity.fifo` models the
link: ready_k = stamp_k + delay, start_k = max(ready_k, start_{k-1}, Z_{k-1}),
Z_k = max(Z_{k-1}, start_k - 8 B / R) + 8 L_k / R, and a frame that finds `limit` frames ready
and not started is dropped. Each frame is released at its start. Because the schedule comes from
the stamps and not from when frames really left, a host freeze delays only the frames due during
it; HTB, which paced before, refilled one frame's worth during a freeze and kept the rest of the
busy period late by it.
"""

from __future__ import annotations

import collections
from dataclasses import dataclass


@dataclass(frozen=True)
class Pacing:
    """A port's token bucket in the delay stage: rate (bit/s), depth (bytes), queue limit (frames)."""

    rate_bps: int
    burst_b: int
    limit_pkts: int

    def item(self) -> str:
        return f"{self.rate_bps},{self.burst_b},{self.limit_pkts}"


class PacedPort:
    """One paced port's virtual FIFO (the same arithmetic as nfqdelay.c's `pace`): `frames`
    holds [ready, start, z_after, length, packet id] of the frames not yet released, oldest first."""

    def __init__(self, pacing: Pacing) -> None:
        self.pacing = pacing
        self.frames: collections.deque[list[int]] = collections.deque()
        self.z = self.last_start = self.z0 = self.start0 = 0
        self.paced = self.drops = 0

    def charge(self, ready: int, length: int, prev_start: int, z: int) -> tuple[int, int]:
        rate, burst = self.pacing.rate_bps, self.pacing.burst_b
        start = max(ready, prev_start, z)
        z = max(z, start - int(burst * 8e9 / rate))
        return start, z + int(length * 8e9 / rate)

    def prune(self, now: int, lead: int) -> None:
        while self.frames and self.frames[0][1] - lead <= now:
            f = self.frames.popleft()
            self.start0, self.z0 = f[1], f[2]

    def admit(self, ready: int, length: int, pid: int) -> int | None:
        """The frame's start, or None: dropped at the queue tail."""
        if self.pacing.limit_pkts:
            waiting = 0  # frames ready and not started at `ready`: starts are non-decreasing
            for f in reversed(self.frames):
                if f[1] <= ready or waiting >= self.pacing.limit_pkts:
                    break
                waiting += 1
            if waiting >= self.pacing.limit_pkts:
                self.drops += 1
                return None
        start, self.z = self.charge(ready, length, self.last_start, self.z)
        self.last_start = start
        self.paced += 1
        self.frames.append([ready, start, self.z, length, pid])
        return start

    def retime(self) -> None:
        """The frames not yet released at the port's (new) rate, as HTB charges at dequeue."""
        prev, z = self.start0, self.z0
        for f in self.frames:
            f[1], f[2] = self.charge(f[0], f[3], prev, z)
            prev, z = f[1], f[2]
        self.last_start, self.z = prev, z

    def summary(self) -> list[int]:
        p = self.pacing
        return [p.rate_bps, p.burst_b, p.limit_pkts, self.paced, self.drops]
