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
   are therefore those of a single, real observation, never a sum of copies. When the run's
   transmissions are known (`transmissions`: the follower's `pid`, as the extraction stage gives
   it), a transmission of the key that never crossed that point is kept once too, at its last
   observation: a replayed copy sent from the attacker's side while the victim's originals die at
   a blackhole, a packet of a detour or a route change, one lost on a link before the point. So
   every transmitted packet of a key counts exactly once; one point alone could not see them all.
3. Order. Packets of a key are ordered by time (integer ns), then capture point, then record number.
4. Termination: a named policy (`uavcas.flows.termination`) cuts a key's packets into flows.
   `connection` (the 5-tuple default): one TCP connection is one flow; it closes on RST or once
   both FINs are sent and the last is acknowledged, packets of the key within a 60 s grace period
   after the close join it (trailing ACKs, retransmissions: no "TCP appendix" flows), a new SYN
   starts a new flow, and the idle (15 s, Cisco NetFlow's inactive timeout) and active (120 s,
   CICFlowMeter's flow timeout) timeouts cut open flows. `cic`: CICFlowMeter's FlowGenerator
   exactly (first backward FIN or any RST closes, a duplicate forward FIN is dropped, 120 s flow
   timeout, no one-packet flows), the appendix artifact included. `timeout`: nfstream's, the
   timeouts only (120 s idle, 1800 s active). The host-pair views have no termination: one flow
   per key per run (`hostpair`) or per window (`window-hostpair`).
5. Cap. Only the first `max_packets` (100,000, the authors' cap) packets of a flow are kept.
6. Direction. The forward direction is the initiator's: the source of the flow's first packet,
   except that a TCP flow whose first packet is a SYN-ACK (the SYN was missed) is turned around so
   the SYN sender is forward (`cic`: always the first packet's source, as CICFlowMeter). In
   `hostpair` the same rule applies to addresses.
7. Minimum size. Flows with fewer than `min_packets` packets are dropped (default 1 for `5tuple`,
   because hping3 floods change source port every packet, 2 under `cic` (CICFlowMeter never
   writes a one-packet flow); 10 for `hostpair` and `window-hostpair`, as in the paper).
8. Numbering. Flows are numbered in order of their first packet (time, point, record number).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

import numpy as np
import pandas as pd

from .packets import PacketTable, payload_and_header
from .termination import (
    DEFAULTS,
    TERMINATIONS,
    Cuts,
    KeyPackets,
    PolicyDefaults,
    Termination,
    cic_cuts,
    connection_cuts,
    timeout_cuts,
)

View = Literal["5tuple", "hostpair", "window-hostpair"]
VIEWS: tuple[str, ...] = ("5tuple", "hostpair", "window-hostpair")
HOST_VIEWS: tuple[str, ...] = ("hostpair", "window-hostpair")  # keys without ports and protocol
HOST_VIEW_MIN_PACKETS = 10  # the paper's filter
MAX_PACKETS_PER_FLOW = 100_000
NS = 1_000_000_000
DEFAULT_TERMINATION = "connection"


@dataclass(frozen=True)
class FlowConfig:
    """Flow rules; a field left None takes the default of the view and termination policy
    (`termination.DEFAULTS`); a timeout of 0 is off."""

    view: View = "5tuple"
    termination: Termination | None = None  # None: `connection` (5tuple); host views have none
    min_packets: int | None = None
    max_packets: int = MAX_PACKETS_PER_FLOW
    idle_timeout_s: float | None = None
    active_timeout_s: float | None = None
    grace_s: float | None = None  # `connection`: how long after its close a flow takes packets
    dedup: bool = True  # one vantage point per flow
    window_t0_unix: float | None = None  # window-hostpair: the plan's t = 0 ...
    window_s: float | None = None  # ... and its window length

    def __post_init__(self) -> None:
        if self.view not in VIEWS:
            raise ValueError(f"unknown flow view {self.view!r}; known: {', '.join(VIEWS)}")
        if self.termination is not None and self.termination not in TERMINATIONS:
            raise ValueError(f"unknown termination policy {self.termination!r}; known: {', '.join(TERMINATIONS)}")
        if self.view in HOST_VIEWS and self.termination not in (None, "timeout"):
            raise ValueError(f"the {self.view} view has no termination policy (one flow per host pair"
                             f"{' per window' if self.view == 'window-hostpair' else ''}); drop --termination")
        if self.view == "window-hostpair" and (self.window_t0_unix is None or not (self.window_s or 0) > 0):
            raise ValueError("the window-hostpair view needs the run's t0 and window length")
        if self.min_packets is not None and self.min_packets < 1:
            raise ValueError("min_packets must be >= 1")
        for name in ("idle_timeout_s", "active_timeout_s", "grace_s"):
            v = getattr(self, name)
            if v is not None and v < 0:
                raise ValueError(f"{name} must be >= 0 (0 = none)")
        if self.grace_s and self.policy != "connection":
            raise ValueError("a close grace period applies to the connection policy only")

    @property
    def policy(self) -> str:
        """The termination policy in force (`timeout` without timeouts for the host-pair views)."""
        if self.view in HOST_VIEWS:
            return "timeout"
        return self.termination or DEFAULT_TERMINATION

    @property
    def defaults(self) -> PolicyDefaults:
        if self.view in HOST_VIEWS:
            return PolicyDefaults(None, None, HOST_VIEW_MIN_PACKETS, 0.0)
        return DEFAULTS[self.policy]

    @property
    def effective_min_packets(self) -> int:
        return self.min_packets if self.min_packets is not None else self.defaults.min_packets

    def _timeout_ns(self, value: float | None, default: float | None) -> int | None:
        v = default if value is None else value
        return int(round(v * NS)) if v else None

    @property
    def idle_ns(self) -> int | None:
        return self._timeout_ns(self.idle_timeout_s, self.defaults.idle_timeout_s)

    @property
    def active_ns(self) -> int | None:
        return self._timeout_ns(self.active_timeout_s, self.defaults.active_timeout_s)

    @property
    def grace_ns(self) -> int:
        return self._timeout_ns(self.grace_s, self.defaults.grace_s) or 0

    @property
    def ends_flows(self) -> bool:
        """Can a flow end before the capture does (so a capture can be streamed)?"""
        return bool(self.idle_ns or self.active_ns or self.policy in ("connection", "cic"))

    def describe(self) -> dict:
        """The rules in force, for dataset cards and file metadata."""
        return {
            "view": self.view, "termination": None if self.view in HOST_VIEWS else self.policy,
            "min_packets": self.effective_min_packets, "max_packets": self.max_packets,
            "idle_timeout_s": (self.idle_ns or 0) / NS or None, "active_timeout_s": (self.active_ns or 0) / NS or None,
            "close_grace_s": self.grace_ns / NS if self.policy == "connection" else None, "dedup": self.dedup,
        }  # fmt: skip


@dataclass(frozen=True)
class Flows:
    """Packets grouped into flows. `order` indexes the packet table; flows are contiguous in it.

    Per packet of `order`: `flow` (flow number), `fwd` (True when sent in the forward direction).
    Per flow: `starts` (offset of its first packet in `order`; `starts[-1] == len(order)` closes),
    `point` (capture point index), `close_ns` (time of the packet that closed it under the
    termination policy, -1 while open: after close_ns + the policy's grace nothing joins it),
    `key` (dense code of the flow's key; a key's later flows have higher flow numbers), `turned`
    (`termination.Cuts.turned`; None: no flow is).
    """

    order: np.ndarray
    flow: np.ndarray
    fwd: np.ndarray
    starts: np.ndarray
    point: np.ndarray
    config: FlowConfig
    close_ns: np.ndarray | None = None
    key: np.ndarray | None = None
    turned: np.ndarray | None = None

    @property
    def n_flows(self) -> int:
        return int(self.starts.shape[0] - 1)

    @property
    def first_sent_forward(self) -> np.ndarray:
        """Per flow: did the forward endpoint (the flow's src) send its first packet?"""
        sent = self.fwd[self.starts[:-1]]
        return sent if self.turned is None else sent != self.turned

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


def _choose_vantage(code: np.ndarray, point: np.ndarray, names: tuple[str, ...],
                    transmissions: np.ndarray | None = None, ts_ns: np.ndarray | None = None) -> np.ndarray:
    """Mask of packets seen at their key's chosen capture point (most packets, ties by name), and
    with `transmissions` (a transmission id per row) the last observation of each transmission
    that never crossed its key's point."""
    n_points = len(names)
    if n_points <= 1:
        return np.ones(code.shape[0], dtype=bool)
    rank = np.argsort(np.argsort(np.asarray(names, dtype=object)))  # point index -> name rank
    n_keys = int(code.max()) + 1 if code.shape[0] else 0
    counts = np.bincount(code * n_points + rank[point], minlength=n_keys * n_points).reshape(n_keys, n_points)
    best_rank = counts.argmax(axis=1)  # argmax returns the first maximum = the smallest name
    keep = rank[point] == best_rank[code]
    if transmissions is None or not code.shape[0]:
        return keep
    tid = np.asarray(transmissions, dtype=np.int64)
    if tid.shape != code.shape or ts_ns is None:
        raise ValueError(f"transmissions: one id per packet expected ({code.shape[0]}), got {tid.shape}")
    crossed = np.zeros(int(tid.max()) + 1, dtype=bool)
    crossed[tid[keep]] = True
    by_tid = np.lexsort((ts_ns, tid))  # each transmission's observations in time order
    last = np.zeros(code.shape[0], dtype=bool)
    last[by_tid[np.r_[np.flatnonzero(tid[by_tid][1:] != tid[by_tid][:-1]), by_tid.shape[0] - 1]]] = True
    return keep | (last & ~crossed[tid])


def _key_packets(p: PacketTable, order: np.ndarray, code: np.ndarray, src_is_a: np.ndarray) -> KeyPackets:
    proto = p["proto"][order]
    payload, _ = payload_and_header(proto, p["ip_len"][order], p["ip_hdr_len"][order], p["l4_hdr_len"][order])
    return KeyPackets(
        ts=p["ts_ns"][order], is_a=src_is_a[order], flags=p["tcp_flags"][order], proto=proto,
        seq=p["tcp_seq"][order].astype(np.int64), ack=p["tcp_ack"][order].astype(np.int64),
        payload=payload, key_starts=_segments(code[order]),
    )  # fmt: skip


def _cuts(kp: KeyPackets, cfg: FlowConfig) -> Cuts:
    if cfg.policy == "connection":
        return connection_cuts(kp, cfg.idle_ns, cfg.active_ns, cfg.grace_ns)
    if cfg.policy == "cic":
        return cic_cuts(kp, cfg.idle_ns, cfg.active_ns)
    return timeout_cuts(kp, cfg.idle_ns, cfg.active_ns)


def assemble(p: PacketTable, cfg: FlowConfig = FlowConfig(), transmissions: np.ndarray | None = None) -> Flows:
    """Group the packets of `p` into flows following the module rules (`transmissions`: one
    transmission id per packet, `flows.follow`'s pid, for rule 2's missed transmissions)."""
    n = len(p)
    if n == 0:
        z = np.zeros(0, dtype=np.int64)
        return Flows(z, z, np.zeros(0, dtype=bool), np.zeros(1, dtype=np.int64), z, cfg, z, z)
    code, src_is_a = _key_codes(p, cfg.view, cfg)
    keep = (_choose_vantage(code, p["point"], p.points, transmissions, p["ts_ns"]) if cfg.dedup
            else np.ones(n, dtype=bool))
    idx = np.flatnonzero(keep)
    order = idx[np.lexsort((p["frame_index"][idx], p["point"][idx], p["ts_ns"][idx], code[idx]))]
    cut = _cuts(_key_packets(p, order, code, src_is_a), cfg)
    flow = np.repeat(np.arange(cut.starts.shape[0] - 1), np.diff(cut.starts))
    # Cap (5) and minimum size (7), counted over the packets the policy keeps in a flow.
    member = cut.keep
    pos = np.cumsum(member) - 1
    pos = pos - np.concatenate(([0], np.cumsum(member)))[cut.starts[:-1]][flow]
    counts = np.bincount(flow[member], minlength=cut.starts.shape[0] - 1)
    ok = member & (pos < cfg.max_packets) & (np.minimum(counts, cfg.max_packets)[flow] >= cfg.effective_min_packets)
    order, flow, fwd = order[ok], flow[ok], cut.fwd[ok]
    kept, flow = np.unique(flow, return_inverse=True) if flow.shape[0] else (np.zeros(0, dtype=np.int64), flow)
    flow = flow.astype(np.int64)
    close_ns = cut.close_ns[kept]
    turned = cut.turned[kept] if cut.turned is not None else None
    # Numbering (8): by first packet (time, point, record number); packets stay in time order.
    starts = _segments(flow) if flow.shape[0] else np.zeros(1, dtype=np.int64)
    first = order[starts[:-1]]
    rank = np.lexsort((p["frame_index"][first], p["point"][first], p["ts_ns"][first]))
    new_id = np.empty_like(rank)
    new_id[rank] = np.arange(rank.shape[0])
    flow = new_id[flow]
    resort = np.argsort(flow, kind="stable")
    order, flow, fwd = order[resort], flow[resort], fwd[resort]
    close_ns = close_ns[rank]
    turned = turned[rank] if turned is not None else None
    starts = _segments(flow) if flow.shape[0] else np.zeros(1, dtype=np.int64)
    first = order[starts[:-1]]
    return Flows(order, flow, fwd, starts, p["point"][first].astype(np.int64), cfg, close_ns, code[first], turned)


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
    close_ns = fl.close_ns[ids] if fl.close_ns is not None else None
    key = fl.key[ids] if fl.key is not None else None
    turned = fl.turned[ids] if fl.turned is not None else None
    return Flows(fl.order[pos], flow, fl.fwd[pos], starts, fl.point[ids], fl.config, close_ns, key, turned)
