"""Transmissions: one IP packet seen at several switches, learnt from the captures alone.

Observations with the same header fields a bridge cannot change (`follow.KEY_COLUMNS`:
addresses, ports, protocol, IP id, TCP seq, flags, TTL, length), each within `MAX_HOP_S` of the
previous, form one transmission; the k-th observation at a switch goes to the k-th transmission.
Its *ingress* is the first switch that saw it; an address's *home switch* is where most of its
transmissions entered, its *usual TTL* the most common TTL of its transmissions. The context
columns (`flows.context`) and the route columns (`flows.routes`) are computed over them.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .follow import KEY_COLUMNS, MAX_HOP_S
from .packets import PacketTable

NS_PER_S = 1_000_000_000


@dataclass(frozen=True)
class Transmissions:
    """Per packet-table row: `tx` (its transmission), `addr_src`, `addr_dst` (dense address codes).
    Per transmission: `ingress` (capture point index of its first observation), `n_points`,
    `t_ns` / `t_last_ns` (first / last observation), `src`, `dst`, `reached`, `offhome` (entered
    at a switch other than its source's home), `ttl_off` (TTL other than its source's usual one).
    `home[a]`: address a's home switch (-1: a never sent)."""

    tx: np.ndarray
    addr_src: np.ndarray
    addr_dst: np.ndarray
    ingress: np.ndarray
    n_points: np.ndarray
    t_ns: np.ndarray
    t_last_ns: np.ndarray
    src: np.ndarray
    dst: np.ndarray
    reached: np.ndarray
    offhome: np.ndarray
    ttl_off: np.ndarray
    home: np.ndarray

    @property
    def delay_ms(self) -> np.ndarray:
        return (self.t_last_ns - self.t_ns) / 1e6


def _address_codes(p: PacketTable) -> tuple[np.ndarray, np.ndarray, int]:
    n = len(p)
    if not n:
        return np.zeros(0, np.int64), np.zeros(0, np.int64), 0
    pairs = np.concatenate([np.stack([p["src_hi"], p["src_lo"]], 1), np.stack([p["dst_hi"], p["dst_lo"]], 1)])
    uniq, inv = np.unique(pairs, axis=0, return_inverse=True)
    inv = inv.reshape(-1).astype(np.int64)
    return inv[:n], inv[n:], int(uniq.shape[0])


def _mode_by(group: np.ndarray, value: np.ndarray, n_groups: int) -> np.ndarray:
    """Most common `value` per group (ties: the smallest value); -1 for groups with none."""
    out = np.full(n_groups, -1, dtype=np.int64)
    if not group.shape[0]:
        return out
    pair, count = np.unique(np.stack([group, value.astype(np.int64)], 1), axis=0, return_counts=True)
    order = np.lexsort((pair[:, 1], -count, pair[:, 0]))  # per group: highest count, then smallest value
    first = np.r_[True, pair[order][1:, 0] != pair[order][:-1, 0]]
    best = pair[order][first]
    out[best[:, 0]] = best[:, 1]
    return out


def transmissions(p: PacketTable, max_hop_s: float = MAX_HOP_S) -> Transmissions:
    """Tie every observation to a transmission; learn each address's home switch and usual TTL."""
    n = len(p)
    ts = np.asarray(p["ts_ns"], dtype=np.int64)
    point = np.asarray(p["point"], dtype=np.int64)
    src, dst, n_addr = _address_codes(p)
    keys = [np.asarray(p[c]) for c in KEY_COLUMNS]
    order = np.lexsort((ts, *reversed(keys)))
    new = np.ones(n, dtype=bool)
    if n > 1:
        new[1:] = np.diff(ts[order]) > int(max_hop_s * NS_PER_S)
        for k in keys:
            ks = k[order]
            new[1:] |= ks[1:] != ks[:-1]
    seg = np.cumsum(new) - 1
    # the k-th observation of a segment at one switch belongs to the segment's k-th transmission
    pt = point[order]
    by_point = np.lexsort((np.arange(n), pt, seg))
    s2, p2 = seg[by_point], pt[by_point]
    starts = np.r_[True, (s2[1:] != s2[:-1]) | (p2[1:] != p2[:-1])] if n else np.zeros(0, bool)
    rank = np.empty(n, dtype=np.int64)
    rank[by_point] = np.arange(n) - np.flatnonzero(starts)[np.cumsum(starts) - 1] if n else 0
    tx_sorted = (np.unique(np.stack([seg, rank], 1), axis=0, return_inverse=True)[1].reshape(-1) if n
                 else np.zeros(0, np.int64))
    tx = np.empty(n, dtype=np.int64)
    tx[order] = tx_sorted
    n_tx = int(tx_sorted.max()) + 1 if n else 0

    by_tx = order[np.argsort(tx_sorted, kind="stable")]  # `order` is time-sorted within a segment
    counts = np.bincount(tx, minlength=n_tx)
    offsets = np.r_[0, np.cumsum(counts)].astype(np.int64)
    first_row, last_row = by_tx[offsets[:-1]], by_tx[offsets[1:] - 1]
    ingress = point[first_row]
    tx_src, tx_dst = src[first_row], dst[first_row]
    ttl = np.asarray(p["ttl"], dtype=np.int64)[first_row]
    home = _mode_by(tx_src, ingress, n_addr)
    usual_ttl = _mode_by(tx_src, ttl, n_addr)
    at_dst_home = (home[dst] >= 0) & (point == home[dst])
    reached = (np.bincount(tx, weights=at_dst_home, minlength=n_tx) > 0) | (home[tx_dst] < 0)
    return Transmissions(
        tx=tx, addr_src=src, addr_dst=dst, ingress=ingress, n_points=counts, t_ns=ts[first_row],
        t_last_ns=ts[last_row], src=tx_src, dst=tx_dst, reached=reached, offhome=ingress != home[tx_src],
        ttl_off=ttl != usual_ttl[tx_src], home=home,
    )
