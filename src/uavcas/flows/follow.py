"""The packet follower: one id per transmitted packet across every capture point it crossed.

A run captures every switch (`s-<node>` points), so one IP packet crossing k switches appears k
times in the packet table. `follow(table, timeline)` tells those observations apart:

* **Identity.** Observations are candidates for the same packet only when everything a switch
  cannot change is equal: addresses, protocol, ports, IP id, TCP sequence number and flags, TTL
  (bridges do not decrement it) and frame length (`KEY_COLUMNS`).
* **Chains.** Candidates are ordered by time and strung into chains, one per transmission: each
  step lasts at most `max_hop_s` and goes where the forwarding in force sent the packet, and
  points are distinct. Candidates that meet all three in one sequence (nearly all packets) are
  chained at once, vectorised; the rest (identical copies in flight together: SYN-ACKs and
  unconnected UDP with IP id 0, duplicate ACKs) go through `copies.match`: FIFO order on each
  link, steps within what the link allows, a copy lost on the link kept from taking the next
  one's observation. Two observations at one point are never merged into one packet.
* **Stamps out of order.** Two switches can stamp one TCP frame out of order. The kernel keeps
  TCP's departure time (a monotonic-clock `skb->tstamp`) across the whole fabric, so no switch
  stamps a TCP frame on receipt: the capture (`skb_tstamp`: none, so the clock when the tap
  runs) and the delay stage (`skb_tstamp_cond`: the clock when it queues the frame) each read
  the clock when they get to it. A capture read after the frame had already crossed the next
  hop (a 0.1 ms hop; a host freeze in between: seen up to 23 ms, all TCP) put it first at the
  next switch. Adjacent observations of one TCP packet whose time order is not a forwarding
  step while the reverse is, within `STAMP_SKEW_S` of each other, are put in forwarding order
  (`_forwarding_order`). Left in time order, the packet split in two and the link it crossed
  lost a frame that its queue did serve: every later frame of that busy period was one frame's
  serialisation late in the audit.
* **Loops.** A frame that comes back to a switch it already crossed, sent there by the
  forwarding in force (a loop while tables change), continues its chain: that observation is a
  `revisit`, which the audit counts as a fidelity failure, not a new packet.
* **Loss.** A packet whose last observation is not its destination's switch left that switch
  towards the next hop of the forwarding in force then and never arrived: it is lost on that
  hop (`Losses`; `to_point` -1 when the switch had no way to the destination at all).

The forwarding comes from a `Timeline`: the tables the run installed (`forwarding.jsonl`,
exact, attacks included) or, for runs made before they were logged, the plan's windows
(`Timeline.from_plan`: each window's routes for the whole window; a wormhole detour travels on alias
MACs outside these tables, so its steps are chained by the planned links).

Output per packet-table row: `pid` (int64, equal across a transmission's observations, numbered
in order of first observation), `hop` (0 at its first switch) and `revisit` (the packet had
already crossed this switch). Pure numpy; no root.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from uavcas.network.forwarding import compute
from uavcas.rundir import ForwardingEpoch, RunDir, RunDirError
from uavcas.twin.model import Plan

from .copies import CapacityFn, LinkBounds, Load, link_bounds, match
from .packets import PacketTable, address_to_words, read_packets

KEY_COLUMNS: tuple[str, ...] = (
    "src_hi", "src_lo", "dst_hi", "dst_lo", "proto", "sport", "dport", "ip_id", "tcp_seq", "tcp_flags",
    "ttl", "frame_len",
)  # fmt: skip
MAX_HOP_S = 1.0  # planned delay + a full queue + scheduling lateness stays far below this
POINT_PREFIX = "s-"  # capture point of node X's switch: s-X (docs/formats.md)
# how far out of order two switches' stamps of one TCP frame can be (module docstring): the host
# freezes it takes, 23 ms seen here, the delay daemon's release stalls up to 34 ms
STAMP_SKEW_S = 0.05
TCP = 6


def node_of_point(point: str) -> str | None:
    return point[len(POINT_PREFIX):] if point.startswith(POINT_PREFIX) else None


class Timeline:
    """The forwarding in force over a run: next-hop tables by time, as arrays.

    `next_hop[e, i, d]` is the node index a frame for node d leaves node i's switch towards in
    epoch e (-1: none); epoch e holds from `t_unix[e]` on, and during `[t_begin_unix[e],
    t_unix[e])` the previous table may still hold for some destinations. `detour_hop[(e, s, d)]`
    overrides it for frames from node s to node d in epoch e (a wormhole detour: the victim's
    traffic with its base station on alias MACs, both ways): node i -> the next switch on the
    detour, -1 off it (where the table holds: a frame sent before the detour, still on its way).
    """

    def __init__(self, nodes: Sequence[str], ips: Sequence[str], epochs: Sequence["ForwardingEpoch"],
                 links: dict[tuple[int, int, int], "LinkBounds"] | None = None) -> None:
        if not epochs:
            raise ValueError("a forwarding timeline needs at least one epoch")
        self.nodes = tuple(nodes)
        index = {n: i for i, n in enumerate(self.nodes)}
        epochs = sorted(epochs, key=lambda e: e.t_unix)
        n = len(self.nodes)
        self.next_hop = np.full((len(epochs), n, n), -1, dtype=np.int32)
        for e, ep in enumerate(epochs):
            for sw, table in ep.next_hop.items():
                for dst, nh in table.items():
                    self.next_hop[e, index[sw], index[dst]] = index[nh]
        self.detour_hop: dict[tuple[int, int, int], np.ndarray] = {}
        for e, ep in enumerate(epochs):
            for hops in ep.detours.values():
                for path in (hops, hops[::-1]):
                    nh = np.full(n, -1, dtype=np.int32)
                    for a, b in zip(path, path[1:]):
                        nh[index[a]] = index[b]
                    self.detour_hop[(e, index[path[0]], index[path[-1]])] = nh
        self.t_unix = np.array([e.t_unix for e in epochs], dtype=np.float64)
        self.t_begin_unix = np.array([e.t_begin_unix for e in epochs], dtype=np.float64)
        self.window = np.array([e.window for e in epochs], dtype=np.int32)
        words = [address_to_words(ip) for ip in ips]
        self._ip_hi = np.array([w[0] for w in words], dtype=np.uint64)
        self._ip_lo = np.array([w[1] for w in words], dtype=np.uint64)
        self.links = links or {}  # (window, i, j) -> what the plan allows a step i -> j

    @classmethod
    def from_epochs(cls, plan: "Plan", epochs: Sequence["ForwardingEpoch"]) -> "Timeline":
        return cls([n.name for n in plan.nodes], [n.ip for n in plan.nodes], epochs, link_bounds(plan))

    @classmethod
    def from_plan(cls, plan: "Plan", t0_unix: float,
                  applied_unix: Sequence[tuple[float, float]] | None = None) -> "Timeline":
        """The plan's forwarding per window (what `Emulation.apply_window` installs).

        `applied_unix`: per window, when its apply began and ended (default: at the planned
        start). Attacks that change forwarding for part of a window are not modelled here.
        """
        names = [n.name for n in plan.nodes]
        epochs = []
        for w in plan.windows:
            fwd = compute(names, [(lk.a, lk.b) for lk in w.links], [r.hops for r in w.routes],
                          detour_links=[(lk.a, lk.b) for lk in w.links if lk.detour])
            t = t0_unix + w.t_s
            begin, end = applied_unix[w.index] if applied_unix is not None and w.index < len(applied_unix) else (t, t)
            epochs.append(ForwardingEpoch(t_begin_unix=begin, t_unix=end, window=w.index, next_hop=fwd.next_hop))
        return cls.from_epochs(plan, epochs)

    def node_of_ip(self, hi: np.ndarray, lo: np.ndarray) -> np.ndarray:
        """Node index of each address (-1: not a node of the plan)."""
        by_lo = np.argsort(self._ip_lo, kind="stable")
        sorted_lo = self._ip_lo[by_lo]
        k = np.minimum(np.searchsorted(sorted_lo, lo), max(sorted_lo.shape[0] - 1, 0))
        if sorted_lo.shape[0] == 0:
            return np.full(hi.shape[0], -1, dtype=np.int32)
        cand = by_lo[k]
        hit = (sorted_lo[k] == lo) & (self._ip_hi[cand] == hi)
        return np.where(hit, cand, -1).astype(np.int32)

    def epoch_at(self, t_unix: np.ndarray) -> np.ndarray:
        """The epoch in force at each time (before the first epoch: the first)."""
        return np.maximum(np.searchsorted(self.t_unix, t_unix, side="right") - 1, 0)

    def window_at(self, t_unix: np.ndarray) -> np.ndarray:
        return self.window[self.epoch_at(t_unix)]

    def hops(self, t_unix: np.ndarray, node: np.ndarray, dst: np.ndarray,
             src: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
        """(next hop in force, next hop of the table being installed) at each time; equal outside
        a change-over. -1 where the node or destination is unknown or has no way there. With
        `src` (node index of each frame's source, -1: none), a wormhole detour in force for the
        source and destination overrides the table (`detour_hop`)."""
        e = self.epoch_at(t_unix)
        ok = (node >= 0) & (dst >= 0)
        ni, di = np.where(ok, node, 0), np.where(ok, dst, 0)
        now = np.where(ok, self.next_hop[e, ni, di], -1)
        e2 = np.minimum(e + 1, self.next_hop.shape[0] - 1)
        switching = (t_unix >= self.t_begin_unix[e2]) & (t_unix < self.t_unix[e2])
        nxt = np.where(ok & switching, self.next_hop[e2, ni, di], now)
        if src is not None and self.detour_hop:
            now, nxt = self._detoured(e, e2, switching, ok, ni, di, src, now, nxt)
        return now, nxt

    def _detoured(self, e, e2, switching, ok, ni, di, src, now, nxt) -> tuple[np.ndarray, np.ndarray]:
        """`hops` where a detour carries the frame: its next switch on the detour. Off the detour
        the table holds (a frame sent before the detour went in, still on its way, has the real
        MAC and follows the table)."""
        now, nxt = now.copy(), nxt.copy()
        for (ep, s, d), nh in self.detour_hop.items():
            hop = nh[ni]
            on = ok & (src == s) & (di == d) & (hop >= 0)
            now = np.where(on & (e == ep), hop, now)
            nxt = np.where(on & (((e2 == ep) & switching) | ((e == ep) & ~switching)), hop, nxt)
        return now, nxt


@dataclass(frozen=True)
class Losses:
    """Packets that left a switch and never reached the next one (one entry per lost packet)."""

    pid: np.ndarray  # int64
    from_point: np.ndarray  # int16, index into the table's points
    to_point: np.ndarray  # int16; -1: the switch had no forwarding entry for the destination
    window: np.ndarray  # int32, window in force at the from point
    t_s: np.ndarray  # float64, time seen at the from point

    def __len__(self) -> int:
        return int(self.pid.shape[0])


@dataclass(frozen=True)
class Crossings:
    """Hop crossings: consecutive observations of one packet (from one switch to the next)."""

    pid: np.ndarray  # int64
    row_from: np.ndarray  # int64, packet-table rows
    row_to: np.ndarray
    from_point: np.ndarray  # int16
    to_point: np.ndarray
    t_from: np.ndarray  # float64, Unix seconds
    t_to: np.ndarray
    window: np.ndarray  # int32, window in force at the from point
    revisit: np.ndarray  # bool: it brought the packet back to a switch it had crossed (a loop)

    def __len__(self) -> int:
        return int(self.pid.shape[0])


@dataclass(frozen=True)
class Followed:
    """The follower's answer for one packet table (see the module docstring)."""

    pid: np.ndarray  # per row, int64
    hop: np.ndarray  # per row, int16
    revisit: np.ndarray  # per row, bool: its packet had crossed this switch before (a loop)
    order: np.ndarray  # rows sorted by (pid, hop)
    offsets: np.ndarray  # pid p's rows are order[offsets[p]:offsets[p + 1]]
    points: tuple[str, ...]
    dst_node: np.ndarray  # per pid, node index of the destination (-1: not a node)
    delivered: np.ndarray  # per pid: last seen at its destination's switch
    losses: Losses
    _ts: np.ndarray
    _point: np.ndarray
    _window: np.ndarray  # per row

    @property
    def n_packets(self) -> int:
        return int(self.offsets.shape[0] - 1)

    def visits(self, pid: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """One packet's observations in hop order: their rows, capture points (indices into
        `points`) and times (Unix s)."""
        rows = self.order[self.offsets[pid]:self.offsets[pid + 1]]
        return rows, self._point[rows], self._ts[rows]

    def path(self, pid: int) -> tuple[list[str], np.ndarray]:
        """The points (names) one packet was seen at, in order, and the times (Unix s)."""
        _, point, ts = self.visits(pid)
        return [self.points[p] for p in point], ts

    def crossings(self) -> Crossings:
        o = self.order
        if o.shape[0] < 2:
            e = np.zeros(0, dtype=np.int64)
            return Crossings(e, e, e, e.astype(np.int16), e.astype(np.int16), e.astype(float), e.astype(float),
                             e.astype(np.int32), e.astype(bool))
        same = self.pid[o[1:]] == self.pid[o[:-1]]
        a, b = o[:-1][same], o[1:][same]
        return Crossings(self.pid[a], a, b, self._point[a], self._point[b], self._ts[a], self._ts[b],
                         self._window[a], self.revisit[b])


def follow(table: PacketTable, timeline: Timeline, max_hop_s: float = MAX_HOP_S,
           capacity: CapacityFn | None = None) -> Followed:
    """Follow every packet of `table` (all capture points of one run); see the module docstring.
    `capacity`: what each port could send by time, where known (`copies.CapacityFn`)."""
    n = len(table)
    ts = np.asarray(table["ts_s"], dtype=np.float64)
    point = np.asarray(table["point"], dtype=np.int16)
    index = {name: i for i, name in enumerate(timeline.nodes)}
    point_node = np.array([index.get(node_of_point(p) or "", -1) for p in table.points] or [-1], dtype=np.int32)
    node = point_node[point] if n else np.zeros(0, dtype=np.int32)
    dst = timeline.node_of_ip(table["dst_hi"], table["dst_lo"]) if n else np.zeros(0, dtype=np.int32)
    src = timeline.node_of_ip(table["src_hi"], table["src_lo"]) if n else np.zeros(0, dtype=np.int32)
    window = timeline.window_at(ts) if n else np.zeros(0, dtype=np.int32)

    keys = [np.asarray(table[c]) for c in KEY_COLUMNS]
    order = np.lexsort((ts, *reversed(keys)))
    new_group = np.ones(n, dtype=bool)
    if n > 1:
        new_group[1:] = np.zeros(n - 1, dtype=bool)
        for k in keys:
            ks = k[order]
            new_group[1:] |= ks[1:] != ks[:-1]
    order, t_order = _forwarding_order(order, new_group, ts, np.asarray(table["proto"]), node, dst, src, timeline)
    t_s, nd, ds, sr = ts[order], node[order], dst[order], src[order]
    gap = np.diff(t_s, prepend=-np.inf)
    new_seg = new_group | (gap > max_hop_s)
    seg = np.cumsum(new_seg) - 1

    # A segment is one packet when its points are distinct and each step is a forwarding step.
    suspect = np.zeros(int(seg[-1]) + 1 if n else 0, dtype=bool)
    if n > 1:
        by_point = np.lexsort((point[order], seg))
        dup = (seg[by_point][1:] == seg[by_point][:-1]) & (point[order][by_point][1:] == point[order][by_point][:-1])
        suspect[seg[by_point][1:][dup]] = True
        step = ~new_seg[1:]
        now, nxt = timeline.hops(t_s[:-1], nd[:-1], ds[:-1], sr[:-1])
        known = (nd[:-1] >= 0) & (ds[:-1] >= 0)
        off_path = step & known & (now != nd[1:]) & (nxt != nd[1:])
        suspect[seg[1:][off_path]] = True

    chain = seg.copy()
    revisit = np.zeros(n, dtype=bool)
    slow = suspect[seg]
    if slow.any():
        rows = np.flatnonzero(slow)
        # where and when each row entered its link: the previous row of its segment (one packet)
        via = np.where(new_seg, -1, np.concatenate([[-1], nd[:-1]])) if n else np.zeros(0, dtype=np.int32)
        t_via = np.concatenate([[-np.inf], t_s[:-1]]) if n else np.zeros(0)
        load = Load(t_s, nd, np.where(slow, -2, via), t_via, np.asarray(table["frame_len"])[order],
                    len(timeline.nodes))
        now, nxt = timeline.hops(t_s[rows], nd[rows], ds[rows], sr[rows])
        chain[rows], revisit_sorted = match(seg[rows], t_s[rows], nd[rows], window[order][rows], now, nxt,
                                            timeline.links, load, max_hop_s, int(seg[-1]) + 1, capacity)
        revisit[order[rows]] = revisit_sorted
    return _assemble(order, chain, revisit, ts, t_order, point, node, dst, src, window, table.points, point_node,
                     timeline)


def _forwarding_order(order: np.ndarray, new_group: np.ndarray, ts: np.ndarray, proto: np.ndarray,
                      node: np.ndarray, dst: np.ndarray, src: np.ndarray,
                      timeline: Timeline) -> tuple[np.ndarray, np.ndarray]:
    """`order` (rows by identity, then time) with each adjacent pair of one packet's observations
    that is stamped out of forwarding order swapped (module docstring), and the times to order
    rows by from here on (`ts` with the two stamps of each swapped pair exchanged)."""
    t_order = ts.copy()
    if order.shape[0] < 2:
        return order, t_order
    a, b = order[:-1], order[1:]
    near = (~new_group[1:] & (ts[b] - ts[a] <= STAMP_SKEW_S) & (proto[a] == TCP) & (node[a] >= 0) & (node[b] >= 0)
            & (dst[a] >= 0))
    k = np.flatnonzero(near)
    if k.shape[0] == 0:
        return order, t_order
    ra, rb = a[k], b[k]
    now_a, nxt_a = timeline.hops(ts[ra], node[ra], dst[ra], src[ra])
    now_b, nxt_b = timeline.hops(ts[rb], node[rb], dst[rb], src[rb])
    forward = (now_a == node[rb]) | (nxt_a == node[rb])
    backward = (now_b == node[ra]) | (nxt_b == node[ra])
    k = k[backward & ~forward]
    k = k[np.concatenate([[True], np.diff(k) > 1])] if k.shape[0] else k  # pairs must not overlap
    order = order.copy()
    ra, rb = order[k].copy(), order[k + 1].copy()
    order[k], order[k + 1] = rb, ra
    t_order[ra], t_order[rb] = ts[rb], ts[ra]
    return order, t_order


def _assemble(order, chain, revisit, ts, t_order, point, node, dst, src, window, points, point_node,
              timeline) -> Followed:
    n = ts.shape[0]
    chain_row = np.empty(n, dtype=np.int64)
    chain_row[order] = chain
    # number packets by first observation (time, then row): stable across identical inputs; an
    # out-of-order pair counts in forwarding order (`t_order`)
    by_time = np.lexsort((np.arange(n), t_order, chain_row)) if n else np.zeros(0, dtype=np.int64)
    c_sorted = chain_row[by_time]
    starts = np.flatnonzero(np.diff(c_sorted, prepend=-1) != 0) if n else np.zeros(0, dtype=np.int64)
    first_rows = by_time[starts]
    rank = np.argsort(np.lexsort((first_rows, t_order[first_rows])), kind="stable")
    pid_of_chain_pos = rank  # chain (in sorted order) -> pid
    seg_index = np.cumsum(np.diff(c_sorted, prepend=-1) != 0) - 1 if n else np.zeros(0, dtype=np.int64)
    pid = np.empty(n, dtype=np.int64)
    pid[by_time] = pid_of_chain_pos[seg_index]
    hop = np.empty(n, dtype=np.int16)
    hop[by_time] = (np.arange(n) - starts[seg_index]).astype(np.int16)
    order_ph = np.lexsort((hop, pid)) if n else np.zeros(0, dtype=np.int64)
    n_pid = int(starts.shape[0])
    counts = np.bincount(pid, minlength=n_pid) if n else np.zeros(0, dtype=np.int64)
    offsets = np.concatenate([[0], np.cumsum(counts)]).astype(np.int64)

    last = order_ph[offsets[1:] - 1] if n_pid else np.zeros(0, dtype=np.int64)
    dst_node = dst[last]
    delivered = (dst_node >= 0) & (node[last] == dst_node)
    now, _ = timeline.hops(ts[last], node[last], dst_node, src[last])
    node_point = np.full(len(timeline.nodes), -1, dtype=np.int16)
    for k, nd in enumerate(point_node[: len(points)]):
        if nd >= 0:
            node_point[nd] = k
    lost = ~delivered & (dst_node >= 0) & (node[last] >= 0)
    lost_pid = np.flatnonzero(lost)
    lr = last[lost]
    to_point = np.where(now[lost] >= 0, node_point[np.maximum(now[lost], 0)], -1).astype(np.int16)
    losses = Losses(lost_pid.astype(np.int64), point[lr], to_point, window[lr].astype(np.int32), ts[lr])
    return Followed(pid, hop, revisit, order_ph, offsets, tuple(points), dst_node, delivered, losses, ts, point,
                    window.astype(np.int32))


def run_timeline(rd: "RunDir", plan: "Plan") -> Timeline:
    """The forwarding a run held: its own log (forwarding.jsonl) when present, else the plan's
    windows at the times run.json says they were applied."""
    epochs = rd.read_forwarding()
    if epochs:
        return Timeline.from_epochs(plan, epochs)
    info, t0 = rd.read_info(), rd.read_t0()
    if t0 is None:
        raise RunDirError(f"{rd.root}: no forwarding.jsonl and no t0 (run.json or {rd.owner_path.name}): "
                          "cannot place windows in time")
    applied = [(a.t_unix - a.timings_s.get("total_s", 0.0), a.t_unix) for a in info.window_applies] if info else []
    return Timeline.from_plan(plan, t0, applied or None)


def follow_run(run_dir: str | Path, max_hop_s: float = MAX_HOP_S, table: PacketTable | None = None,
               allow_truncated: bool = True) -> tuple[PacketTable, Followed]:
    """Read a run directory's captures (unless `table` is given) and follow its packets along
    the forwarding the run held (`run_timeline`)."""
    rd = RunDir(Path(run_dir))
    plan = rd.read_plan()
    if table is None:
        table = read_packets(rd.pcaps(), allow_truncated=allow_truncated)
    return table, follow(table, run_timeline(rd, plan), max_hop_s)
