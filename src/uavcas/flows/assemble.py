"""Packets -> bidirectional flows (keys, de-duplication, termination, caps, direction), vectorised.

Rules, in the order they are applied:
1. Key. `5tuple`: the unordered pair of endpoints (address, port) plus the IP protocol, so both
   directions of a conversation share a key. `hostpair` (the authors' key, offered for parity):
   the unordered address pair, ports and protocol ignored. `window-hostpair` (the paper's
   granularity): the host pair per plan window, window k = floor((t - t0) / window_s), so one
   flow per host pair per window (needs `window_t0_unix` and `window_s`).
2. Vantage point (de-duplication). A packet crossing several switches is captured once per
   switch. For each key we keep the packets of ONE capture point: the point that saw the most
   packets of that key, ties broken by the point name (alphabetically first). Counts and bytes
   are therefore those of a single, real observation, never a sum of copies.
3. Order. Packets of a key are ordered by time (integer ns), then capture point, then record number.
4. Termination. A key's packets are cut into flows; every rule looks only at earlier packets, so
   a capture read in blocks gives the same flows as one read whole (`uavcas.flows.stream`).
   a. FIN/RST (CICFlowMeter's FlowGenerator): a packet with RST, or the first FIN sent in the
      backward direction, is the flow's last packet; the next packet of the key starts a new
      flow. A flow's first packet never ends it (CICFlowMeter checks flags only when adding).
   b. New connection: a TCP SYN without ACK starts a new flow, unless it repeats the SYN that
      opened the flow (same sender and sequence number: a retransmission). hping3 floods and
      restarted clients reuse 5-tuples; without this rule separate connection attempts merge.
   c. Idle timeout: a gap >= `idle_timeout_s` since the key's previous packet starts a new flow.
   d. Active timeout (CICFlowMeter's flow timeout): a packet more than `active_timeout_s`
      after its flow's first packet starts a new flow.
   Defaults per view (`VIEW_RULES`): `5tuple` uses a-d with an idle timeout of 15 s (the default
   inactive timeout of Cisco NetFlow; longer than any gap inside the twin's benign flows, which
   send every 0.1 s or close with FIN, and shorter than the gap between separate attack bursts
   of a run, issue #12) and CICFlowMeter's 120 s active timeout. CICFlowMeter itself has neither
   b nor c: `FlowConfig(idle_timeout_s=0, syn_restart=False)` reproduces its flow boundaries.
   `hostpair` (the authors' generator): no termination, one flow per key per run.
5. Cap. Only the first `max_packets` (100,000, the authors' cap) packets of a flow are kept.
6. Direction. The forward direction is the initiator's: the source of the flow's first packet,
   except that a TCP flow whose first packet is a SYN-ACK (the SYN was missed) is turned around so
   the SYN sender is forward. In `hostpair` the same rule applies to addresses.
7. Minimum size. Flows with fewer than `min_packets` packets are dropped (default 1 for `5tuple`,
   because hping3 floods change source port every packet; 10 for `hostpair` and
   `window-hostpair`, as in the paper).
8. Numbering. Flows are numbered in order of their first packet (time, point, record number).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

import numpy as np
import pandas as pd

from .packets import PacketTable

View = Literal["5tuple", "hostpair", "window-hostpair"]
VIEWS: tuple[str, ...] = ("5tuple", "hostpair", "window-hostpair")
HOST_VIEWS: tuple[str, ...] = ("hostpair", "window-hostpair")  # keys without ports and protocol
MAX_PACKETS_PER_FLOW = 100_000
TCP_FIN, TCP_SYN, TCP_RST, TCP_ACK = 0x01, 0x02, 0x04, 0x10
NS = 1_000_000_000
DEFAULT_IDLE_TIMEOUT_S = 15.0  # Cisco NetFlow's default inactive timeout
CIC_ACTIVE_TIMEOUT_S = 120.0  # CICFlowMeter's flowTimeout (120,000,000 us)


@dataclass(frozen=True)
class ViewRules:
    min_packets: int
    idle_timeout_s: float | None
    active_timeout_s: float | None
    fin_rst: bool
    syn_restart: bool


VIEW_RULES: dict[str, ViewRules] = {
    "5tuple": ViewRules(1, DEFAULT_IDLE_TIMEOUT_S, CIC_ACTIVE_TIMEOUT_S, True, True),
    "hostpair": ViewRules(10, None, None, False, False),
    "window-hostpair": ViewRules(10, None, None, False, False),  # the window cuts the flows
}
DEFAULT_MIN_PACKETS: dict[str, int] = {v: r.min_packets for v, r in VIEW_RULES.items()}


@dataclass(frozen=True)
class FlowConfig:
    """Flow rules; a field left None takes the view's default (`VIEW_RULES`); a timeout of 0 is off."""

    view: View = "5tuple"
    min_packets: int | None = None
    max_packets: int = MAX_PACKETS_PER_FLOW
    idle_timeout_s: float | None = None
    active_timeout_s: float | None = None
    fin_rst: bool | None = None
    syn_restart: bool | None = None
    dedup: bool = True  # one vantage point per flow
    window_t0_unix: float | None = None  # window-hostpair: the plan's t = 0 ...
    window_s: float | None = None  # ... and its window length

    def __post_init__(self) -> None:
        if self.view not in VIEWS:
            raise ValueError(f"unknown flow view {self.view!r}; known: {', '.join(VIEWS)}")
        if self.view == "window-hostpair" and (self.window_t0_unix is None or not (self.window_s or 0) > 0):
            raise ValueError("the window-hostpair view needs the run's t0 and window length")
        if self.min_packets is not None and self.min_packets < 1:
            raise ValueError("min_packets must be >= 1")
        for name in ("idle_timeout_s", "active_timeout_s"):
            v = getattr(self, name)
            if v is not None and v < 0:
                raise ValueError(f"{name} must be >= 0 (0 = none)")

    @property
    def rules(self) -> ViewRules:
        return VIEW_RULES[self.view]

    @property
    def effective_min_packets(self) -> int:
        return self.min_packets if self.min_packets is not None else self.rules.min_packets

    def _timeout_ns(self, value: float | None, default: float | None) -> int | None:
        v = default if value is None else value
        return int(round(v * NS)) if v else None

    @property
    def idle_ns(self) -> int | None:
        return self._timeout_ns(self.idle_timeout_s, self.rules.idle_timeout_s)

    @property
    def active_ns(self) -> int | None:
        return self._timeout_ns(self.active_timeout_s, self.rules.active_timeout_s)

    @property
    def effective_fin_rst(self) -> bool:
        return self.rules.fin_rst if self.fin_rst is None else self.fin_rst

    @property
    def effective_syn_restart(self) -> bool:
        return self.rules.syn_restart if self.syn_restart is None else self.syn_restart

    def describe(self) -> dict:
        """The rules in force, for dataset cards and file metadata."""
        return {
            "view": self.view, "min_packets": self.effective_min_packets, "max_packets": self.max_packets,
            "idle_timeout_s": (self.idle_ns or 0) / NS or None, "active_timeout_s": (self.active_ns or 0) / NS or None,
            "fin_rst": self.effective_fin_rst, "syn_restart": self.effective_syn_restart, "dedup": self.dedup,
        }  # fmt: skip


@dataclass(frozen=True)
class Flows:
    """Packets grouped into flows. `order` indexes the packet table; flows are contiguous in it.

    Per packet of `order`: `flow` (flow number), `fwd` (True when sent in the forward direction).
    Per flow: `starts` (offset of its first packet in `order`; `starts[-1] == len(order)` closes),
    `point` (capture point index), `closed` (ended by rule 4a: no later packet can join it),
    `key` (dense code of the flow's key; a key's later flows have higher flow numbers).
    """

    order: np.ndarray
    flow: np.ndarray
    fwd: np.ndarray
    starts: np.ndarray
    point: np.ndarray
    config: FlowConfig
    closed: np.ndarray | None = None
    key: np.ndarray | None = None

    @property
    def n_flows(self) -> int:
        return int(self.starts.shape[0] - 1)

    @property
    def first(self) -> np.ndarray:
        """Index (into the packet table) of each flow's first packet."""
        return self.order[self.starts[:-1]]

    @property
    def last(self) -> np.ndarray:
        """Index (into the packet table) of each flow's last packet."""
        return self.order[self.starts[1:] - 1]

    def packet_flow(self, n_packets: int) -> np.ndarray:
        """Flow number of every packet of the table, -1 where a packet belongs to no kept flow."""
        out = np.full(n_packets, -1, dtype=np.int64)
        out[self.order] = self.flow
        return out


def _segments(key: np.ndarray) -> np.ndarray:
    """Start offsets of runs of equal values in a sorted array, closed by len."""
    change = np.flatnonzero(key[1:] != key[:-1]) + 1
    return np.concatenate(([0], change, [key.shape[0]])).astype(np.int64)


def _key_codes(p: PacketTable, view: str, cfg: FlowConfig | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Dense key code per packet and whether the packet's source is the key's 'a' endpoint."""
    shi, slo, dhi, dlo = p["src_hi"], p["src_lo"], p["dst_hi"], p["dst_lo"]
    if view in HOST_VIEWS:
        sp = dp = np.zeros(len(p), dtype=np.uint16)
        proto = np.zeros(len(p), dtype=np.uint8)
    else:
        sp, dp, proto = p["sport"], p["dport"], p["proto"]
    # Lexicographic (hi, lo, port) comparison decides which endpoint is 'a'.
    src_is_a = (shi < dhi) | ((shi == dhi) & ((slo < dlo) | ((slo == dlo) & (sp <= dp))))
    cols = {
        "ahi": np.where(src_is_a, shi, dhi),
        "alo": np.where(src_is_a, slo, dlo),
        "bhi": np.where(src_is_a, dhi, shi),
        "blo": np.where(src_is_a, dlo, slo),
        # ports and protocol packed in one integer: fewer columns to hash
        "pp": (np.where(src_is_a, sp, dp).astype(np.int64) << 24)
        | (np.where(src_is_a, dp, sp).astype(np.int64) << 8)
        | proto.astype(np.int64),
    }
    if not (cols["ahi"].any() or cols["bhi"].any()):  # all IPv4: the high words carry nothing
        del cols["ahi"], cols["bhi"]
    if view == "window-hostpair" and cfg is not None:
        t0_ns, win_ns = round(cfg.window_t0_unix * 1e9), round(cfg.window_s * 1e9)
        cols["win"] = (p["ts_ns"].astype(np.int64) - t0_ns) // win_ns
    codes = pd.DataFrame(cols).groupby(list(cols), sort=False).ngroup().to_numpy(np.int64)
    return codes, src_is_a


def _choose_vantage(code: np.ndarray, point: np.ndarray, names: tuple[str, ...]) -> np.ndarray:
    """Mask of packets seen at their key's chosen capture point (most packets, ties by name)."""
    n_points = len(names)
    if n_points <= 1:
        return np.ones(code.shape[0], dtype=bool)
    rank = np.argsort(np.argsort(np.asarray(names, dtype=object)))  # point index -> name rank
    n_keys = int(code.max()) + 1 if code.shape[0] else 0
    counts = np.bincount(code * n_points + rank[point], minlength=n_keys * n_points).reshape(n_keys, n_points)
    best_rank = counts.argmax(axis=1)  # argmax returns the first maximum = the smallest name
    return rank[point] == best_rank[code]


def _orientation(first_is_a: np.ndarray, first_flags: np.ndarray, first_proto: np.ndarray) -> np.ndarray:
    """Forward = 'a' endpoint sends forward? (rule 6: the first packet's source, SYN-ACK turned)."""
    synack = (first_proto == 6) & ((first_flags & (TCP_SYN | TCP_ACK)) == (TCP_SYN | TCP_ACK))
    return np.where(synack, ~first_is_a, first_is_a)


def _idle_starts(ts: np.ndarray, key_start: np.ndarray, cfg: FlowConfig) -> np.ndarray:
    """Rule 4c (and the key boundaries): packets that start a flow whatever the flow held."""
    new = key_start.copy()
    if cfg.idle_ns is not None and ts.shape[0] > 1:
        new[1:] |= np.diff(ts) >= cfg.idle_ns
    return new


def _cut_sequential(ts, is_a, flags, proto, seq, starts: np.ndarray, cfg: FlowConfig) -> np.ndarray:
    """Rules 4a, 4b and 4d on top of `starts` (sorted segment starts, closed by n): all flow starts.

    Each depends on the current flow (its orientation, its first packet's time and SYN), so a cut
    creates a new segment that is examined again; each pass handles every open segment at once.
    """
    n = ts.shape[0]
    fin_rst, active, syn = cfg.effective_fin_rst, cfg.active_ns, cfg.effective_syn_restart
    if n == 0 or not (fin_rst or active or syn):
        return starts
    rst = (flags & TCP_RST) != 0 if fin_rst else np.zeros(n, dtype=bool)
    fin = (flags & TCP_FIN) != 0 if fin_rst else np.zeros(n, dtype=bool)
    pure_syn = (proto == 6) & ((flags & (TCP_SYN | TCP_ACK)) == TCP_SYN) if syn else np.zeros(n, dtype=bool)
    seg_s, seg_e = starts[:-1], starts[1:]
    # only segments that could be cut need examining
    marks = (rst | fin | pure_syn).astype(np.int64)
    maybe = np.add.reduceat(marks, seg_s) - marks[seg_s] > 0
    if active:
        maybe |= (ts[seg_e - 1] - ts[seg_s]) > active
    sel = maybe & (seg_e - seg_s > 1)
    todo_s, todo_e = seg_s[sel], seg_e[sel]
    cuts: list[np.ndarray] = []
    while todo_s.shape[0]:
        length = todo_e - todo_s
        seg = np.repeat(np.arange(todo_s.shape[0]), length)
        pos = np.arange(length.sum()) - np.repeat(np.cumsum(length) - length, length) + np.repeat(todo_s, length)
        first = todo_s[seg]
        fwd_a = _orientation(is_a[todo_s], flags[todo_s], proto[todo_s])[seg]
        later = pos > first  # a flow's first packet never ends or restarts it
        # 4a: a packet that ends the flow -> the flow is cut after it
        cut_at = np.where(later & (rst[pos] | (fin[pos] & (is_a[pos] != fwd_a))), pos + 1, n + 1)
        # 4b: a new SYN starts a new flow unless it repeats the flow's opening SYN
        again = pure_syn[first] & (seq[pos] == seq[first]) & (is_a[pos] == is_a[first])
        cut_at = np.minimum(cut_at, np.where(later & pure_syn[pos] & ~again, pos, n + 1))
        if active:  # 4d: a packet too long after the first starts a new flow
            cut_at = np.minimum(cut_at, np.where(ts[pos] - ts[first] > active, pos, n + 1))
        best = np.minimum.reduceat(cut_at, np.cumsum(length) - length)
        ok = best < todo_e
        cuts.append(best[ok])
        todo_s, todo_e = best[ok], todo_e[ok]
        keep = todo_e - todo_s > 1
        todo_s, todo_e = todo_s[keep], todo_e[keep]
    if not cuts:
        return starts
    return np.unique(np.concatenate([starts, *cuts]))


def assemble(p: PacketTable, cfg: FlowConfig = FlowConfig()) -> Flows:
    """Group the packets of `p` into flows following the module rules."""
    n = len(p)
    if n == 0:
        z = np.zeros(0, dtype=np.int64)
        return Flows(z, z, np.zeros(0, dtype=bool), np.zeros(1, dtype=np.int64), z, cfg, np.zeros(0, dtype=bool), z)
    code, src_is_a = _key_codes(p, cfg.view, cfg)
    keep = _choose_vantage(code, p["point"], p.points) if cfg.dedup else np.ones(n, dtype=bool)
    idx = np.flatnonzero(keep)
    order = idx[np.lexsort((p["frame_index"][idx], p["point"][idx], p["ts_ns"][idx], code[idx]))]
    ts, is_a = p["ts_ns"][order], src_is_a[order]
    flags, proto, seq = p["tcp_flags"][order], p["proto"][order], p["tcp_seq"][order]
    key_start = np.zeros(order.shape[0], dtype=bool)
    key_start[_segments(code[order])[:-1]] = True
    hard = np.flatnonzero(_idle_starts(ts, key_start, cfg))
    starts = _cut_sequential(ts, is_a, flags, proto, seq, np.append(hard, order.shape[0]), cfg)
    flow = np.repeat(np.arange(starts.shape[0] - 1), np.diff(starts))
    # Closed (4a): the flow's last packet ended it, so nothing later can join (used when streaming).
    last = starts[1:] - 1
    fwd_a_all = _orientation(is_a[starts[:-1]], flags[starts[:-1]], proto[starts[:-1]])
    closed = np.zeros(starts.shape[0] - 1, dtype=bool)
    if cfg.effective_fin_rst:
        closed = (last > starts[:-1]) & (((flags[last] & TCP_RST) != 0) | (((flags[last] & TCP_FIN) != 0) & (is_a[last] != fwd_a_all)))
    # Cap (5) and minimum size (7).
    pos = np.arange(order.shape[0]) - starts[:-1][flow]
    counts = np.diff(starts)
    ok = (pos < cfg.max_packets) & (np.minimum(counts, cfg.max_packets)[flow] >= cfg.effective_min_packets)
    order, flow, is_a = order[ok], flow[ok], is_a[ok]
    kept, flow = np.unique(flow, return_inverse=True) if flow.shape[0] else (np.zeros(0, dtype=np.int64), flow)
    flow = flow.astype(np.int64)
    fwd_a, closed = fwd_a_all[kept], closed[kept]
    # Numbering (8): by first packet (time, point, record number); packets stay in time order.
    starts = _segments(flow) if flow.shape[0] else np.zeros(1, dtype=np.int64)
    first = order[starts[:-1]]
    rank = np.lexsort((p["frame_index"][first], p["point"][first], p["ts_ns"][first]))
    new_id = np.empty_like(rank)
    new_id[rank] = np.arange(rank.shape[0])
    flow = new_id[flow]
    resort = np.argsort(flow, kind="stable")
    order, flow, is_a = order[resort], flow[resort], is_a[resort]
    fwd_a, closed = fwd_a[rank], closed[rank]
    starts = _segments(flow) if flow.shape[0] else np.zeros(1, dtype=np.int64)
    fwd = is_a == fwd_a[flow]
    first = order[starts[:-1]]
    return Flows(order, flow, fwd, starts, p["point"][first].astype(np.int64), cfg, closed, code[first])


def select_flows(fl: Flows, keep: np.ndarray, max_packets: int | None = None, min_packets: int = 1) -> Flows:
    """The flows of `fl` where `keep`, capped to `max_packets` and at least `min_packets` long."""
    counts = np.diff(fl.starts)
    capped = np.minimum(counts, max_packets) if max_packets is not None else counts
    keep = keep & (capped >= min_packets)
    ids = np.flatnonzero(keep)
    length = capped[ids]
    pos = np.repeat(fl.starts[ids], length) + (np.arange(length.sum()) - np.repeat(np.cumsum(length) - length, length))
    flow = np.repeat(np.arange(ids.shape[0]), length)
    starts = np.concatenate(([0], np.cumsum(length))).astype(np.int64)
    closed = fl.closed[ids] if fl.closed is not None else None
    key = fl.key[ids] if fl.key is not None else None
    return Flows(fl.order[pos], flow, fl.fwd[pos], starts, fl.point[ids], fl.config, closed, key)
