"""IP fragments join their datagram's 5-tuple flow.

Only a datagram's first fragment (offset 0) carries the transport header. Every later fragment
is matched to the first fragment of the same datagram, i.e. the same (source, destination,
protocol, IP id / IPv6 fragment id), nearest in time within the reassembly timeout, and takes
its ports, so the whole datagram lands in one flow (reordered fragments, sent before their
first fragment, match too). A later fragment whose first fragment is not in the capture
(within the timeout either side) is an orphan: it is left out of the flows and counted
(`CaptureStats.orphan_fragments`, reported on stderr by the command line).

Timeouts: Linux's reassembly timeouts, `net.ipv4.ipfrag_time` = 30 s and `net.ipv6.ip6frag_time`
= 60 s (RFC 8200 section 4.5).

The resolver keeps state across blocks of a capture read in chunks: first fragments of the last
timeout are remembered, later fragments still waiting for theirs are carried to the next block.
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from .decode import FRAG_FIRST, FRAG_LATER

NS = 1_000_000_000
REASSEMBLY_TIMEOUT_NS = {4: 30 * NS, 6: 60 * NS}
_KEY = ("src_hi", "src_lo", "dst_hi", "dst_lo", "proto", "ip_id")


class FragmentResolver:
    """Ports for later fragments, one capture file at a time (feed its blocks in order)."""

    def __init__(self) -> None:
        self.firsts: pd.DataFrame | None = None  # recent first fragments: key, ts_ns, sport, dport
        self.pending: dict[str, np.ndarray] | None = None  # later fragments not matched yet
        self.orphans = 0

    def resolve(self, cols: dict[str, np.ndarray], final: bool) -> dict[str, np.ndarray]:
        """`cols` of one block with later fragments given ports (or held back / dropped)."""
        frag = cols["frag"]
        if self.pending is not None:
            cols = {k: np.concatenate([self.pending[k], cols[k]]) for k in cols}
            frag = cols["frag"]
            self.pending = None
        first = frag == FRAG_FIRST
        later = frag == FRAG_LATER
        if first.any():
            new = pd.DataFrame({k: cols[k][first] for k in (*_KEY, "ts_ns", "sport", "dport", "ip_version")})
            self.firsts = new if self.firsts is None else pd.concat([self.firsts, new], ignore_index=True)
        if not later.any():
            self._prune(cols, final)
            return cols
        li = np.flatnonzero(later)
        matched = np.zeros(li.shape[0], dtype=bool)
        if self.firsts is not None and len(self.firsts):
            lat = pd.DataFrame({k: cols[k][li] for k in (*_KEY, "ts_ns", "ip_version")})
            lat["row"] = np.arange(li.shape[0])
            m = lat.merge(self.firsts, on=list(_KEY), suffixes=("", "_f"))
            if len(m):
                m["dt"] = (m["ts_ns"] - m["ts_ns_f"]).abs()
                limit = np.where(m["ip_version"].to_numpy() == 4, REASSEMBLY_TIMEOUT_NS[4], REASSEMBLY_TIMEOUT_NS[6])
                m = m[m["dt"].to_numpy() <= limit]
                best = m.sort_values(["row", "dt"], kind="stable").drop_duplicates("row")
                rows = best["row"].to_numpy()
                cols["sport"][li[rows]] = best["sport"].to_numpy()
                cols["dport"][li[rows]] = best["dport"].to_numpy()
                matched[rows] = True
        waiting = li[~matched]
        drop = np.zeros(frag.shape[0], dtype=bool)
        if waiting.shape[0]:
            drop[waiting] = True
            horizon = int(cols["ts_ns"].max()) if cols["ts_ns"].shape[0] else 0
            age = horizon - cols["ts_ns"][waiting]
            limit = np.where(cols["ip_version"][waiting] == 4, REASSEMBLY_TIMEOUT_NS[4], REASSEMBLY_TIMEOUT_NS[6])
            expired = final | (age > limit)
            self.orphans += int(expired.sum())
            keep_waiting = waiting[~expired]
            if keep_waiting.shape[0]:
                self.pending = {k: v[keep_waiting] for k, v in cols.items()}
        self._prune(cols, final)
        return {k: v[~drop] for k, v in cols.items()} if drop.any() else cols

    def _prune(self, cols: dict[str, np.ndarray], final: bool) -> None:
        if self.firsts is None or not len(self.firsts):
            return
        if final:
            self.firsts = None
            return
        horizon = int(cols["ts_ns"].max()) if cols["ts_ns"].shape[0] else None
        if horizon is not None:
            self.firsts = self.firsts[self.firsts["ts_ns"].to_numpy() >= horizon - REASSEMBLY_TIMEOUT_NS[6]]
