"""The shaping each link direction held over a run: what the port applied to a frame, when.

The emulator shapes direction i -> j on one port (`emulation.shaping`); each window change
rewrites the port's delay, rate, loss and queue limit *in place*, in the first phase of the
apply (`Emulation.apply_links`, logged as the forwarding epoch's `t_begin_unix`). Frames queued
at that moment stay in the queue and are sent at the *new* rate (HTB charges a frame at dequeue,
with the class's rate then), and a link that leaves the plan keeps its last shaping while its
queue drains. So the model looks parameters up by time, not by the window a frame arrived in:
`PortShaping.at(t)` is the setting in force at time t.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from uavcas.flows.follow import Timeline
from uavcas.twin.model import Plan


@dataclass(frozen=True)
class PortShaping:
    """Piecewise-constant shaping of one link direction: setting k holds from `t_s[k]` on."""

    t_s: np.ndarray  # float64, Unix s, ascending: the apply that installed the setting began
    until_s: np.ndarray  # ... and ended: the port changed somewhere in [t_s, until_s)
    window: np.ndarray  # int64, the plan window the setting came from
    delay_ms: np.ndarray
    rate_mbps: np.ndarray
    loss: np.ndarray

    def at(self, t_s: np.ndarray) -> np.ndarray:
        """Index of the setting in force at each time (-1: the port was not shaped yet)."""
        return np.searchsorted(self.t_s, t_s, side="right") - 1

    def queue_limit_pkts(self, k: np.ndarray, netem: bool = False) -> np.ndarray:
        """The queue limit of settings k, as the shaper sized it from the rate (`emulation.shaping`):
        the pfifo's, or with netem, netem's own (it also holds the frames in their delay)."""
        # lazily: reading a run needs no emulation package (docs/architecture.md, dependencies)
        from uavcas.emulation.shaping import netem_limit_pkts, queue_limit_pkts

        if netem:
            return np.array([netem_limit_pkts(float(r), float(d)) for r, d in zip(self.rate_mbps[k], self.delay_ms[k])],
                            dtype=np.int64)
        return np.array([queue_limit_pkts(float(r)) for r in self.rate_mbps[k]], dtype=np.int64)


def port_shaping(plan: Plan, timeline: Timeline) -> dict[tuple[int, int], PortShaping]:
    """(i, j) node indices -> the shaping direction i -> j held, from the run's applies.

    Each epoch whose window differs from the one before installs that window's links (re-applies
    of the same window for an attack change no shaping: `Shaper._changed`)."""
    index = {x.name: x.index for x in plan.nodes}
    rows: dict[tuple[int, int], list[tuple[float, float, int, float, float, float]]] = {}
    last = None
    for t, until, w in zip(timeline.t_begin_unix.tolist(), timeline.t_unix.tolist(), timeline.window.tolist()):
        if w == last or not 0 <= w < len(plan.windows):
            continue
        last = w
        for lk in plan.windows[w].links:
            i, j = index[lk.a], index[lk.b]
            for key in ((i, j), (j, i)):
                rows.setdefault(key, []).append((t, max(t, until), w, lk.delay_ms, lk.rate_mbps, lk.loss))
    out = {}
    for key, r in rows.items():
        a = np.array(r, dtype=np.float64)
        out[key] = PortShaping(a[:, 0], a[:, 1], a[:, 2].astype(np.int64), a[:, 3], a[:, 4], a[:, 5])
    return out
