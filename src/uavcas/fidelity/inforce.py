"""The shaping each link direction held over a run: what the port applied to a frame, when.

The emulator shapes direction i -> j on one port (`emulation.shaping`); each window change
rewrites the port's delay, rate, loss and queue limit *in place*, in the first phase of the
apply (`Emulation.apply_links`, logged as the forwarding epoch's `t_begin_unix`). Frames queued
at that moment stay in the queue and are sent at the *new* rate (HTB charges a frame at dequeue,
with the class's rate then), and a link that leaves the plan keeps its last shaping while its
queue drains. So the model looks parameters up by time, not by the window a frame arrived in:
`PortShaping.at(t)` is the setting in force at time t.

An attack that shapes links otherwise for part of a window (a jammer: `Window.link_overrides`)
re-shapes them in place at its logged start and stop (`AttackExecutor.reshape`): those instants
split the window into segments (0: as the window was applied, k: after its k-th reshape), each
with the parameters then in force, the overrides of the attacks active then (`ShapeSpan`: their
logged [start, stop) and when each reshape began and ended). The sampler counts the kernel's
counters per segment the same way (shaping.jsonl `segment`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from uavcas.flows.follow import Timeline
from uavcas.network.queues import netem_limit_pkts, queue_limit_pkts
from uavcas.twin.model import Plan


@dataclass(frozen=True)
class PortShaping:
    """Piecewise-constant shaping of one link direction: setting k holds from `t_s[k]` on."""

    t_s: np.ndarray  # float64, Unix s, ascending: the apply that installed the setting began
    until_s: np.ndarray  # ... and ended: the port changed somewhere in [t_s, until_s)
    window: np.ndarray  # int64, the plan window the setting came from
    segment: np.ndarray  # int64, its segment of the window (module docstring)
    delay_ms: np.ndarray
    rate_mbps: np.ndarray
    loss: np.ndarray

    def at(self, t_s: np.ndarray) -> np.ndarray:
        """Index of the setting in force at each time (-1: the port was not shaped yet)."""
        return np.searchsorted(self.t_s, t_s, side="right") - 1

    def queue_limit_pkts(self, k: np.ndarray, netem: bool = False) -> np.ndarray:
        """The queue limit of settings k, as the shaper sized it from the rate (`network.queues`):
        the pfifo's, or with netem, netem's own (it also holds the frames in their delay)."""
        if netem:
            return np.array([netem_limit_pkts(float(r), float(d)) for r, d in zip(self.rate_mbps[k], self.delay_ms[k])],
                            dtype=np.int64)
        return np.array([queue_limit_pkts(float(r)) for r in self.rate_mbps[k]], dtype=np.int64)


@dataclass(frozen=True)
class PortCapacity:
    """`flows.copies.CapacityFn` over a run's `port_shaping`: the bits port i -> j could send in
    [a, b) at the rates it held (each setting from its apply's start)."""

    shaping: dict[tuple[int, int], PortShaping]

    def __call__(self, i: int, j: int, a: float, b: float) -> float | None:
        ps = self.shaping.get((i, j))
        if ps is None or b <= a or a < ps.t_s[0]:
            return None
        edges = np.clip(np.append(ps.t_s, np.inf), a, b)
        return float(np.sum(np.diff(edges) * ps.rate_mbps) * 1e6)


@dataclass(frozen=True)
class ShapeSpan:
    """An attack that re-shapes links while active: its logged [start, stop), and when its
    start's reshape began and its stop's ended (the logged times where the log has no such)."""

    attack_id: str
    start_unix: float
    stop_unix: float
    from_unix: float
    until_unix: float

    def active(self, t: float) -> bool:
        return self.start_unix <= t < self.stop_unix


def shape_spans(records) -> list[ShapeSpan]:
    """The spans of the attack log's (`RunDir.read_attacks`) attacks, paired start to stop."""
    starts = {r.attack_id: r for r in records if getattr(r, "event", None) == "start"}
    out = []
    for r in records:
        if getattr(r, "event", None) == "stop" and r.attack_id in starts:
            a = starts[r.attack_id]
            out.append(ShapeSpan(r.attack_id, a.t_unix, r.t_unix, a.shaping_from_unix or a.t_unix,
                                 r.shaping_until_unix or r.t_unix))
    return out


def port_shaping(plan: Plan, timeline: Timeline, spans: list[ShapeSpan] = ()) -> dict[tuple[int, int], PortShaping]:
    """(i, j) node indices -> the shaping direction i -> j held, from the run's applies and the
    reshapes of the attacks in `spans` (module docstring).

    Each epoch whose window differs from the one before installs that window's links (re-applies
    of the same window for an attack change no shaping: `Shaper._changed`)."""
    index = {x.name: x.index for x in plan.nodes}
    by_id = {sp.attack_id: sp for sp in spans}
    rows: dict[tuple[int, int], list[tuple[float, float, int, int, float, float, float]]] = {}
    epochs, last = [], None
    for t, until, w in zip(timeline.t_begin_unix.tolist(), timeline.t_unix.tolist(), timeline.window.tolist()):
        if w != last and 0 <= w < len(plan.windows):
            epochs.append((t, until, w))
            last = w
    for k, (t, until, w) in enumerate(epochs):
        win = plan.windows[w]
        t_next = epochs[k + 1][0] if k + 1 < len(epochs) else np.inf
        mine = [by_id[a] for a in dict.fromkeys(o.attack_id for o in win.link_overrides) if a in by_id]
        # (setting from, until, the time that says which attacks are active)
        changes = [(t, max(t, until), t)]
        for sp in mine:
            if t < sp.start_unix < t_next:
                changes.append((sp.from_unix, max(sp.from_unix, sp.start_unix), sp.start_unix))
            if t < sp.stop_unix < t_next:
                changes.append((sp.stop_unix, max(sp.stop_unix, sp.until_unix), sp.stop_unix))
        changes.sort(key=lambda c: c[2])
        for seg, (a, b, at) in enumerate(changes):
            on = {sp.attack_id for sp in mine if sp.active(at)}
            over = {(o.src, o.dst): o for o in win.link_overrides if o.attack_id in on}
            for lk in win.links:
                for src, dst in ((lk.a, lk.b), (lk.b, lk.a)):
                    p = over.get((src, dst), lk)
                    rows.setdefault((index[src], index[dst]), []).append(
                        (a, b, w, seg, p.delay_ms, p.rate_mbps, p.loss))
    out = {}
    for key, r in rows.items():
        a = np.array(r, dtype=np.float64)
        out[key] = PortShaping(a[:, 0], a[:, 1], a[:, 2].astype(np.int64), a[:, 3].astype(np.int64), a[:, 4],
                               a[:, 5], a[:, 6])
    return out


def planned_settings(shaping: dict[tuple[int, int], PortShaping]) -> dict[tuple[int, int, int, int],
                                                                          tuple[float, float, float]]:
    """(window, segment, i, j) -> the planned (delay_ms, rate_mbps, loss) of that setting."""
    return {(int(w), int(sg), i, j): (float(d), float(r), float(lo)) for (i, j), ps in shaping.items()
            for w, sg, d, r, lo in zip(ps.window, ps.segment, ps.delay_ms, ps.rate_mbps, ps.loss)}
