"""Identical copies in flight together: which observation belongs to which transmission.

The follower (`follow`) chains most packets at once; the rest are segments of byte-identical
observations of several transmissions at once (SYN-ACKs and unconnected UDP with IP id 0,
duplicate ACKs, a flood's reused header). `match` strings them into chains, observation by
observation in time order, with what a link can and cannot do:

* **FIFO.** A link is FIFO (the delay stage and the HTB rate stage both are), so copies leave a
  link in the order they entered it: of the open chains on one link, an observation goes to the
  *oldest* that it can be the next step of. (Picking the chain whose step is closest to the
  planned delay, as the follower once did, swaps copies under queueing: the real step is planned
  delay + queue wait.) Between chains on different links into the switch, which FIFO does not
  order, the shorter queue wait wins.
* **Bounds** (`LinkBounds`). A step is no shorter than the link's planned delay (less `EARLY_S`)
  and no longer than the planned delay plus a full queue drained at the planned rate (plus
  `LATE_S`); a jammer's override in the window widens both.
* **A copy lost on the link** must not take the next copy's observation: pairing the
  observation with an older copy means that copy waited in the queue, so the port was busy
  sending frames that entered before it all that time. When the port could have sent those
  frames (`Load`: an upper bound) `BUSY_SLACK_S` before the observation, at the rates it held
  (the caller's `CapacityFn`: the audit knows them) or else at the window's slowest, the older
  copy was lost and the observation goes to a younger one (`lost_on_link`).
* **Loops.** An observation at a switch that a chain already crossed continues that chain only
  when the forwarding in force sent the frame back there and the step fits the link: the
  frame looped (`revisit`). Otherwise it is a new transmission, and a chain never takes two
  observations at one point in a row.

Among the chains on one link, one whose step the link allows ranks above one the forwarding
log sent there (an unforeseen forwarding is likelier than an impossible step). Chains that are
neither expected nor joined by a link to the observation's switch are skipped; where no chain
fits, the observation starts a new one.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from uavcas.network.queues import MTU_FRAME_B, full_queue_s
from uavcas.twin.model import Plan

EARLY_S = 0.001  # a step may be this much shorter than the planned delay (pcap stamps, timer slack)
LATE_S = 0.005  # ... and this much longer than planned delay + a full queue (scheduling lateness)
# a queue wait that the port's traffic cannot account for by more than this (the p99 delay-error
# tolerance: lateness the emulator may have) means the copy was lost, not late
BUSY_SLACK_S = 0.0005

# the bits port i -> j could send in [a, b) at the rates it held, where the caller knows them
# (the audit: the shaping the run applied, a jammer's included); None: the plan's slowest rate
CapacityFn = Callable[[int, int, float, float], float | None]


@dataclass(frozen=True)
class LinkBounds:
    """What the plan allows one step i -> j in one window (every setting of the window, a jammer's
    override included): the planned delay, and how long a frame can wait in the link's queue."""

    delay_min_s: float
    delay_max_s: float
    rate_min_bps: float

    @property
    def wait_max_s(self) -> float:
        """A full queue drained at the slowest rate."""
        return full_queue_s(self.rate_min_bps / 1e6)

    def admits(self, step_s: float) -> bool:
        return self.delay_min_s - EARLY_S <= step_s <= self.delay_max_s + self.wait_max_s + LATE_S


def link_bounds(plan: Plan) -> dict[tuple[int, int, int], LinkBounds]:
    """(window, i, j) -> `LinkBounds`, both directions of every link of every window."""
    idx = {n.name: n.index for n in plan.nodes}
    out = {}
    for w in plan.windows:
        for lk in w.links:
            for a, b in ((lk.a, lk.b), (lk.b, lk.a)):
                ov = [o for o in w.link_overrides if (o.src, o.dst) == (a, b)]
                delays = [lk.delay_ms] + [o.delay_ms for o in ov]
                rates = [lk.rate_mbps] + [o.rate_mbps for o in ov]
                out[(w.index, idx[a], idx[b])] = LinkBounds(min(delays) / 1000.0, max(delays) / 1000.0,
                                                            max(min(rates), 1e-3) * 1e6)
    return out


class Load:
    """The frames each port delivered: how long a frame can have waited behind others.

    A frame counts for port i -> j when the follower's fast path saw it step from i to j (an
    unambiguous packet: when it entered at i, when it left at j). A frame that entered after a
    copy is behind it in the FIFO and cannot delay it; a frame that left before the copy was
    ready did not either. An ambiguous frame seen at j (its step is what `match` is working out)
    counts for every port into j whenever it left, so the load is an upper bound."""

    def __init__(self, t_out: np.ndarray, node: np.ndarray, via: np.ndarray, t_in: np.ndarray,
                 frame_len: np.ndarray, n_nodes: int) -> None:
        """Rows seen at `node`'s switch at `t_out`, having entered the link at `via`'s switch at
        `t_in` (via -1: from no port, the first observation; -2: ambiguous, t_in unknown)."""
        self.n = n_nodes
        use = (node >= 0) & (via != -1)
        key = np.where(via[use] >= 0, via[use] * n_nodes + node[use], n_nodes * n_nodes + node[use])
        # ports: by entry time (FIFO: the order they leave in); ambiguous frames: by exit time
        t_in_u = np.where(via[use] >= 0, t_in[use], t_out[use])
        order = np.lexsort((t_out[use], t_in_u, key))
        self._key, self._in, self._out = key[order], t_in_u[order], t_out[use][order]
        # exits in entry order, made non-decreasing per port (searchable; FIFO up to capture jitter)
        base = float(self._out[0]) if self._out.shape[0] else 0.0
        span = float(self._out[-1] - base) + 1.0 if self._out.shape[0] else 1.0
        self._out_mono = np.maximum.accumulate(self._key * span + (self._out - base)) - self._key * span + base
        self._bits = np.concatenate([[0.0], np.cumsum(frame_len[use][order].astype(np.float64) * 8.0)])

    def _range(self, key: int) -> tuple[int, int]:
        return int(np.searchsorted(self._key, key, side="left")), int(np.searchsorted(self._key, key, side="right"))

    def ahead(self, i: int, j: int, t_in: float, t_a: float, t_b: float) -> float:
        """Bits that port i -> j can have sent in [t_a, t_b) ahead of a frame that entered at t_in."""
        lo, hi = self._range(i * self.n + j)
        k_in = lo + int(np.searchsorted(self._in[lo:hi], t_in, side="left"))
        k_a = lo + int(np.searchsorted(self._out_mono[lo:k_in], t_a, side="left"))
        port = float(self._bits[k_in] - self._bits[k_a])
        lo, hi = self._range(self.n * self.n + j)
        a = lo + int(np.searchsorted(self._out[lo:hi], t_a, side="left"))
        b = lo + int(np.searchsorted(self._out[lo:hi], t_b, side="left"))
        return port + float(self._bits[b] - self._bits[a])


def lost_on_link(link: LinkBounds, load: Load, i: int, j: int, t_in: float, t_out: float,
                 capacity: CapacityFn | None = None) -> bool:
    """Whether a copy that entered link i -> j at t_in cannot be the frame seen at j at t_out: it
    would have waited longer than the port can have been busy, so it would have left earlier.

    Waiting from when it was ready until t_out, the port would have had to be sending all that
    time: the frames ahead of it (`Load.ahead`, an upper bound) and the rate stage's debt from
    before it was ready (at most the cost of the frame sent last, which j saw within one MTU
    frame's time before). When the port could have sent all that (`capacity`, the rates it
    held; without it, the window's slowest) `BUSY_SLACK_S` before t_out, the copy was lost."""
    ready = t_in + link.delay_max_s
    if t_out - ready <= BUSY_SLACK_S:
        return False
    mtu_s = MTU_FRAME_B * 8.0 / link.rate_min_bps
    ahead = load.ahead(i, j, t_in, t_in + link.delay_min_s - mtu_s, t_out)
    cap = capacity(i, j, ready, t_out - BUSY_SLACK_S) if capacity is not None else None
    if cap is None:
        cap = (t_out - BUSY_SLACK_S - ready) * link.rate_min_bps
    return cap > ahead


@dataclass
class _Chain:
    id: int
    node: int  # where it was last seen
    t: float  # when
    window: int  # the window in force then
    visited: set[int] = field(default_factory=set)
    expected: set[int] = field(default_factory=set)  # where the forwarding sent it from there


def match(seg: np.ndarray, t: np.ndarray, node: np.ndarray, window: np.ndarray, now: np.ndarray, nxt: np.ndarray,
          links: dict[tuple[int, int, int], LinkBounds], load: Load, max_hop_s: float,
          first_id: int, capacity: CapacityFn | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Chain ids (from `first_id`) and revisit flags of rows of ambiguous segments (rows in time
    order within each segment); `now`, `nxt`: the next hops in force at each row (`Timeline.hops`)."""
    out = np.empty(seg.shape[0], dtype=np.int64)
    revisit = np.zeros(seg.shape[0], dtype=bool)
    next_id = first_id
    last_seg = -1
    chains: list[_Chain] = []
    for r in range(seg.shape[0]):
        if seg[r] != last_seg:
            last_seg, chains = seg[r], []
        p, tr = int(node[r]), float(t[r])
        # FIFO within each link (the oldest chain on it), then across links the shortest queue wait
        per_link: dict[int, tuple[tuple[bool, bool, bool, float, int], float, _Chain]] = {}
        for c in chains:
            cost = _cost(c, p, tr, links, load, max_hop_s, capacity)
            if cost is not None and (c.node not in per_link or cost[0] < per_link[c.node][0]):
                per_link[c.node] = (*cost, c)
        best, best_cost = None, None
        for rank, wait, c in per_link.values():
            if best_cost is None or (*rank[:3], wait) < best_cost:
                best, best_cost = c, (*rank[:3], wait)
        if best is None:
            best = _Chain(next_id, p, tr, int(window[r]))
            next_id += 1
            chains.append(best)
        else:
            revisit[r] = best_cost[0]
        best.node, best.t, best.window = p, tr, int(window[r])
        best.visited.add(p)
        best.expected = {int(h) for h in (now[r], nxt[r]) if h >= 0}
        out[r] = best.id
    return out, revisit


def _cost(c: _Chain, p: int, tr: float, links: dict[tuple[int, int, int], LinkBounds], load: Load,
          max_hop_s: float, capacity: CapacityFn | None) -> tuple[tuple[bool, bool, bool, float, int], float] | None:
    """How well an observation at p at time tr continues chain c (None: it cannot): the rank
    among chains on the same link (a loop, outside what the link allows, not where the
    forwarding sent it, oldest first: FIFO), and the queue wait it implies (step - planned
    delay). A step the link cannot make ranks below a forwarding the log did not foresee."""
    dt = tr - c.t
    if dt < 0 or dt > max_hop_s or c.node == p:
        return None
    expected = p in c.expected
    link = links.get((c.window, c.node, p)) if p >= 0 and c.node >= 0 else None
    if not expected and c.expected and link is None:
        return None  # forwarding sends it elsewhere and no link joins the two switches
    fits = link is None or (link.admits(dt) and not lost_on_link(link, load, c.node, p, c.t, tr, capacity))
    loop = p in c.visited
    if loop and not (expected and fits):
        return None  # only the forwarding brings a frame back, over a step the link allows
    return (loop, not fits, not expected, c.t, c.id), abs(dt - (link.delay_max_s if link is not None else 0.0))
