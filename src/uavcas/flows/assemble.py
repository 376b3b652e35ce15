"""Packets -> bidirectional flows (keys, de-duplication, timeouts, caps, direction), vectorised.

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
3. Order. Packets of a key are ordered by timestamp, then by record number within the file.
4. Timeouts (optional; default none, as in the paper: one flow per key per run). A packet starts
   a new flow when its gap to the previous packet of the key is >= `idle_timeout_s`, or when it
   comes >= `active_timeout_s` after the first packet of the current flow (nfstream semantics).
5. Cap. Only the first `max_packets` (100,000) packets of a flow are kept; later ones are dropped.
6. Direction. The forward direction is the initiator's: the source of the flow's first packet,
   except that a TCP flow whose first packet is a SYN-ACK (the SYN was missed) is turned around so
   the SYN sender is forward. In `hostpair` the same rule applies to addresses.
7. Minimum size. Flows with fewer than `min_packets` packets are dropped (default 1 for `5tuple`,
   because hping3 floods change source port every packet; 10 for `hostpair` and
   `window-hostpair`, as in the paper).
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
DEFAULT_MIN_PACKETS: dict[str, int] = {"5tuple": 1, "hostpair": 10, "window-hostpair": 10}
TCP_SYN, TCP_ACK = 0x02, 0x10


@dataclass(frozen=True)
class FlowConfig:
    view: View = "5tuple"
    min_packets: int | None = None  # None: the view's default
    max_packets: int = MAX_PACKETS_PER_FLOW
    idle_timeout_s: float | None = None
    active_timeout_s: float | None = None
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

    @property
    def effective_min_packets(self) -> int:
        return self.min_packets if self.min_packets is not None else DEFAULT_MIN_PACKETS[self.view]


@dataclass(frozen=True)
class Flows:
    """Packets grouped into flows. `order` indexes the packet table; flows are contiguous in it.

    Per packet of `order`: `flow` (flow number), `fwd` (True when sent in the forward direction).
    Per flow: `starts` (offset of its first packet in `order`; `starts[-1] == len(order)` closes),
    `point` (capture point index), `fwd_src_is_a` (internal orientation, see `packet_src`).
    """

    order: np.ndarray
    flow: np.ndarray
    fwd: np.ndarray
    starts: np.ndarray
    point: np.ndarray
    config: FlowConfig

    @property
    def n_flows(self) -> int:
        return int(self.starts.shape[0] - 1)

    @property
    def first(self) -> np.ndarray:
        """Index (into the packet table) of each flow's first packet."""
        return self.order[self.starts[:-1]]

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
        cols["win"] = np.floor((p["ts_s"] - cfg.window_t0_unix) / cfg.window_s).astype(np.int64)
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


def _split_by_timeouts(ts: np.ndarray, starts: np.ndarray, cfg: FlowConfig) -> np.ndarray:
    """Boolean 'starts a new flow' per packet of key-sorted packets (key starts given)."""
    new = np.zeros(ts.shape[0], dtype=bool)
    new[starts[:-1]] = True
    if cfg.idle_timeout_s is not None and ts.shape[0] > 1:
        new[1:] |= np.diff(ts) >= cfg.idle_timeout_s
    if cfg.active_timeout_s is not None:
        seg = _segments(np.cumsum(new))
        long = np.flatnonzero(ts[seg[1:] - 1] - ts[seg[:-1]] >= cfg.active_timeout_s)
        for s in long:  # rare: only flows longer than the active timeout need the sequential rule
            begin = ts[seg[s]]
            for i in range(seg[s] + 1, seg[s + 1]):
                if ts[i] - begin >= cfg.active_timeout_s:
                    new[i] = True
                    begin = ts[i]
    return new


def assemble(p: PacketTable, cfg: FlowConfig = FlowConfig()) -> Flows:
    """Group the packets of `p` into flows following the module rules."""
    n = len(p)
    if n == 0:
        z = np.zeros(0, dtype=np.int64)
        return Flows(z, z, np.zeros(0, dtype=bool), np.zeros(1, dtype=np.int64), z, cfg)
    code, src_is_a = _key_codes(p, cfg.view, cfg)
    keep = _choose_vantage(code, p["point"], p.points) if cfg.dedup else np.ones(n, dtype=bool)
    idx = np.flatnonzero(keep)
    order = idx[np.lexsort((p["frame_index"][idx], p["point"][idx], p["ts_s"][idx], code[idx]))]
    ts = p["ts_s"][order]
    new = _split_by_timeouts(ts, _segments(code[order]), cfg)
    flow = np.cumsum(new) - 1
    starts = _segments(flow)
    # Cap: position within the flow must be below max_packets.
    pos = np.arange(order.shape[0]) - starts[:-1][flow]
    counts = np.diff(starts)
    ok = (pos < cfg.max_packets) & (np.minimum(counts, cfg.max_packets)[flow] >= cfg.effective_min_packets)
    order, flow = order[ok], flow[ok]
    flow = np.unique(flow, return_inverse=True)[1].astype(np.int64) if flow.shape[0] else flow
    starts = _segments(flow) if flow.shape[0] else np.zeros(1, dtype=np.int64)
    first = order[starts[:-1]]
    fwd_is_a = src_is_a[first].copy()
    fl = p["tcp_flags"][first]
    synack = (p["proto"][first] == 6) & ((fl & (TCP_SYN | TCP_ACK)) == (TCP_SYN | TCP_ACK))
    fwd_is_a[synack] = ~fwd_is_a[synack]
    fwd = src_is_a[order] == fwd_is_a[flow]
    return Flows(order, flow, fwd, starts, p["point"][first].astype(np.int64), cfg)
