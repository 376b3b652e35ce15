"""Episodes: one row per plan node per plan window (the `window-host` view), features and labels.

Why a unit other than the flow: a composition's attacks share a victim but no single 5-tuple flow
carries two of them (one effect per packet; a blackhole drops the victim's sessions, a flood
makes new ones), so the paper's collaborative classes (Blackhole+DoS, ...) are empty in the
5-tuple view. They are defined on the victim over time, which is what an episode is: a host's
traffic in one plan window. A victim hit by a blackhole and a flood in one window is
'Blackhole+DoS' here.

Rules (`host_window_frame`):
- Packets: the observations the 5-tuple flows kept (`Flows.order`: one capture point per flow,
  and a transmission that missed it at its last one, so a packet seen at three switches counts
  once), each placed in window
  k = floor((t - t0) / window_s), clipped to the plan's windows as `TruthContext.window` places
  packets for the attack rules (traffic before t = 0 counts in window 0, after the last window in
  the last one). A packet belongs to the episode of its source node (sent, `_out`) and to that of
  its destination node (received, `_in`); addresses that are no plan node have no episodes.
- Packet features: counts, bytes (frame bytes on the wire), rates per second of window, the span
  between the first and last packet (`active_s`), distinct peer addresses and peer ports (TCP/UDP
  ports of the other end), TCP SYN (without ACK), SYN-ACK, RST and FIN counts, UDP and ICMP
  (ICMPv6 included) shares of the host's packets.
- Flow features: the 5-tuple flows that START in window k (window of their first packet) with
  the host as an endpoint: how many (`flows`; `flows_out` when the host initiated them), and the
  mean and max of a subset of the standard's features (its `episode_summary`,
  `uavcas.flows.standards`) and of every context column (`ctx_*`, when the flow frame has them).
  A flow is summarised once, in its first window, even when its packets continue into later
  windows (those packets do count in the later episodes' packet features).
- Route context (with the context columns): `ctx_pkt_route_lonely_frac`, `ctx_pkt_path_len_shift`,
  `ctx_pkt_delay_shift_ms`, `ctx_pkt_off_own_route_frac`, `ctx_pkt_passing_off_route_frac`,
  `ctx_pkt_lonely_off_route_frac`, the means over the episode's packets of their transmission's
  route measures (`flows.routes`; 0 where none is defined), and the largest of each over one
  peer's packets (`ctx_pkt_route_lonely_max`, `ctx_pkt_path_len_shift_peer_max`,
  `ctx_pkt_delay_shift_peer_max_ms`, `ctx_pkt_off_own_route_max`, `ctx_pkt_passing_off_route_max`,
  `ctx_pkt_lonely_off_route_max`). Unlike the flow summaries they
  see a stream that began in an earlier window.
- NaN/inf: a flow feature that is inf (a rate over a zero duration) or NaN is left out of the mean
  and max; a summary over no finite value (no flow starts in the window, for instance) is NaN,
  as is `flows`' summaries on such rows. `uavcas.load_dataset` then sets NaN and inf to 0, as for
  flows. Packet features are always finite.
- Truth and labels: `attack_packets` = the episode's packets with an attack effect
  (`PacketTruth.family >= 0`: made, moved, dropped or provoked), `provoked_packets` those of them
  an attack provoked, per family `attack_packets_<family>`; `label_<family>` when one of
  its packets has an effect of that family; `label` = `schema.class_name` of those families,
  `label_source` the families' label sources as in `labels.label`.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np
import pandas as pd

from uavcas.attacks import family
from uavcas.flows.assemble import Flows
from uavcas.flows.packets import PacketTable, address_to_words, ns_to_s
from uavcas.flows.routes import episode_route_context
from uavcas.flows.standards import DEFAULT_STANDARD
from uavcas.flows.standards import standard as feature_standard
from uavcas.flows.termination import TCP_ACK, TCP_FIN, TCP_RST, TCP_SYN
from uavcas.schema import (
    CONTEXT_FEATURES,
    EPISODE_PACKET_UNITS,
    EPISODE_STATS,
    FAMILIES,
    class_name,
)
from uavcas.vocabulary import ATTACK_PACKET_COLUMNS, EFFECTS

from .effects import PacketTruth
from .label import SOURCES

if TYPE_CHECKING:
    from uavcas.flows.context import PacketRoutes
    from uavcas.twin.model import Plan

NS = 1_000_000_000
IP_TCP, IP_UDP, IP_ICMP, IP_ICMPV6 = 6, 17, 1, 58


def _node_index(hi: np.ndarray, lo: np.ndarray, plan: "Plan") -> np.ndarray:
    """Index into plan.nodes of each address, -1 where it is no node's (a loop over the few nodes)."""
    out = np.full(hi.shape[0], -1, dtype=np.int64)
    for k, nd in enumerate(plan.nodes):
        h, l = address_to_words(nd.ip)
        out[(hi == np.uint64(h)) & (lo == np.uint64(l))] = k
    return out


def _windows(ts_ns: np.ndarray, t0_unix: float, window_s: float, n_windows: int) -> np.ndarray:
    """Plan window of each time (exact integer ns), clipped to [0, n_windows - 1]."""
    t0_ns, win_ns = round(t0_unix * NS), round(window_s * NS)
    return np.clip((ts_ns.astype(np.int64) - t0_ns) // win_ns, 0, max(n_windows - 1, 0))


def _count(g: np.ndarray, n: int, mask: np.ndarray | None = None) -> np.ndarray:
    w = None if mask is None else mask.astype(np.float64)
    return np.bincount(g, weights=w, minlength=n).astype(np.int64) if g.shape[0] else np.zeros(n, dtype=np.int64)


def _distinct(g: np.ndarray, value: np.ndarray, n: int) -> np.ndarray:
    """Per group: number of distinct values."""
    if g.shape[0] == 0:
        return np.zeros(n, dtype=np.int64)
    pairs = np.unique(np.stack([g.astype(np.int64), value.astype(np.int64)], axis=1), axis=0)
    return np.bincount(pairs[:, 0], minlength=n).astype(np.int64)


def _summaries(g: np.ndarray, values: pd.DataFrame, n: int) -> dict[str, np.ndarray]:
    """`<col>_mean` and `<col>_max` per group over finite values (NaN where none)."""
    finite = values.replace([np.inf, -np.inf], np.nan)
    agg = finite.groupby(g).agg(list(EPISODE_STATS)) if len(finite) else None
    out: dict[str, np.ndarray] = {}
    for c in values.columns:
        for s in EPISODE_STATS:
            col = np.full(n, np.nan)
            if agg is not None:
                col[agg.index.to_numpy()] = agg[(c, s)].to_numpy(dtype=np.float64)
            out[f"{c}_{s}"] = col
    return out


def host_window_frame(
    packets: PacketTable,
    flows: Flows,
    flow_frame: pd.DataFrame,
    truth: PacketTruth,
    plan: "Plan",
    t0_unix: float,
    standard: str = DEFAULT_STANDARD,
    routes: "PacketRoutes | None" = None,
) -> pd.DataFrame:
    """One row per (plan node, plan window) with at least one packet (module docstring).

    `flows` must be 5-tuple flows of `packets` and `flow_frame` their frame (row i = flow i, the
    standard's features, and the `ctx_*` columns when context is wanted); `truth` is per row of
    `packets`; `routes` (with the context) the packets' route shifts, summarised over the
    episode's own packets (`schema.EPISODE_ROUTE_FEATURES`). Rows are ordered by node (plan
    order), then window.
    """
    if flows.config.view != "5tuple":
        raise ValueError(f"episodes are built from 5-tuple flows, not {flows.config.view!r} ones")
    if len(flow_frame) != flows.n_flows:
        raise ValueError(f"flow_frame has {len(flow_frame)} rows for {flows.n_flows} flows")
    n_win = len(plan.windows)
    rows = flows.order
    src = _node_index(packets["src_hi"][rows], packets["src_lo"][rows], plan)
    dst = _node_index(packets["dst_hi"][rows], packets["dst_lo"][rows], plan)
    ts = packets["ts_ns"][rows].astype(np.int64)
    win = _windows(ts, t0_unix, plan.window_s, n_win)

    # One entry per (packet, endpoint node): out for the source node, in for the destination node
    # (a packet from a node to itself, which the emulation never sends, would count as sent only).
    out_k, in_k = np.flatnonzero(src >= 0), np.flatnonzero((dst >= 0) & (dst != src))
    pk = np.concatenate([out_k, in_k])
    host = np.concatenate([src[out_k], dst[in_k]])
    is_out = np.concatenate([np.ones(out_k.shape[0], dtype=bool), np.zeros(in_k.shape[0], dtype=bool)])
    code = host * n_win + win[pk]
    groups, g = np.unique(code, return_inverse=True)
    g = g.astype(np.int64)
    n = groups.shape[0]
    row = rows[pk]  # packet-table row of each entry

    size = packets["frame_len"][row].astype(np.int64)
    proto = packets["proto"][row]
    flags = packets["tcp_flags"][row].astype(np.int64)
    tcp = proto == IP_TCP
    syn = tcp & ((flags & (TCP_SYN | TCP_ACK)) == TCP_SYN)
    synack = tcp & ((flags & (TCP_SYN | TCP_ACK)) == (TCP_SYN | TCP_ACK))
    rst, fin = tcp & ((flags & TCP_RST) != 0), tcp & ((flags & TCP_FIN) != 0)
    is_in = ~is_out
    total = _count(g, n)
    first_ns = np.full(n, np.iinfo(np.int64).max)
    last_ns = np.full(n, np.iinfo(np.int64).min)
    np.minimum.at(first_ns, g, ts[pk])
    np.maximum.at(last_ns, g, ts[pk])
    # the other end of each entry: the destination of a sent packet, the source of a received one
    peer_hi = np.where(is_out, packets["dst_hi"][row], packets["src_hi"][row])
    peer_lo = np.where(is_out, packets["dst_lo"][row], packets["src_lo"][row])
    _, peer = np.unique(np.stack([peer_hi, peer_lo], axis=1), axis=0, return_inverse=True) if n else (None, np.zeros(0))
    ported = tcp | (proto == IP_UDP)
    peer_port = np.where(is_out, packets["dport"][row], packets["sport"][row]).astype(np.int64)

    cols: dict[str, np.ndarray] = {
        "packets_out": _count(g, n, is_out), "packets_in": _count(g, n, is_in),
        "bytes_out": np.bincount(g, weights=np.where(is_out, size, 0), minlength=n).astype(np.int64),
        "bytes_in": np.bincount(g, weights=np.where(is_in, size, 0), minlength=n).astype(np.int64),
    }  # fmt: skip
    cols["packets_per_s"] = total / plan.window_s
    cols["bytes_per_s"] = (cols["bytes_out"] + cols["bytes_in"]) / plan.window_s
    cols["active_s"] = (last_ns - first_ns) / 1e9
    cols["peers"] = _distinct(g, peer.ravel(), n)
    cols["peer_ports"] = _distinct(g[ported], peer_port[ported], n)
    for name, mask in (("syn", syn), ("synack", synack), ("rst", rst), ("fin", fin)):
        cols[f"{name}_out"] = _count(g, n, mask & is_out)
        cols[f"{name}_in"] = _count(g, n, mask & is_in)
    cols["udp_share"] = _count(g, n, proto == IP_UDP) / total
    cols["icmp_share"] = _count(g, n, (proto == IP_ICMP) | (proto == IP_ICMPV6)) / total

    # Flows starting in the window, at both their endpoint nodes (the first packet's two addresses).
    first = flows.first
    f_src = _node_index(packets["src_hi"][first], packets["src_lo"][first], plan)
    f_dst = _node_index(packets["dst_hi"][first], packets["dst_lo"][first], plan)
    f_win = _windows(packets["ts_ns"][first], t0_unix, plan.window_s, n_win)
    # the forward endpoint (initiator) is the first packet's source unless it travels backward
    f_fwd = flows.fwd[flows.starts[:-1]] if flows.n_flows else np.zeros(0, dtype=bool)
    ini = np.where(f_fwd, f_src, f_dst)
    a_k, b_k = np.flatnonzero(f_src >= 0), np.flatnonzero((f_dst >= 0) & (f_dst != f_src))
    fk = np.concatenate([a_k, b_k])
    f_host = np.concatenate([f_src[a_k], f_dst[b_k]])
    f_code = f_host * n_win + f_win[fk]
    pos = np.searchsorted(groups, f_code)
    # a flow's first packet is one of the episode's packets, so its group exists
    assert np.array_equal(groups[np.minimum(pos, max(n - 1, 0))], f_code) if n else fk.shape[0] == 0
    cols["flows"] = _count(pos, n)
    cols["flows_out"] = _count(pos, n, ini[fk] == f_host)
    cols["flows_in"] = cols["flows"] - cols["flows_out"]
    subset = dict(feature_standard(standard).episode_summary)
    values = flow_frame[list(subset)].iloc[fk].rename(columns=subset).reset_index(drop=True).astype(np.float64)
    ctx = [c for c in CONTEXT_FEATURES if c in flow_frame.columns]
    if ctx:
        values = pd.concat([values, flow_frame[ctx].iloc[fk].reset_index(drop=True).astype(np.float64)], axis=1)
    cols.update(_summaries(pos, values, n))
    if ctx:
        if routes is None:
            raise ValueError("the flows' context columns come with the packets' routes (flows.context.context_frames)")
        cols.update(episode_route_context(g, routes.tx[row], peer.ravel(), routes.shifts, n))
    assert set(EPISODE_PACKET_UNITS) <= set(cols)

    # truth and labels
    fam = truth.family[row].astype(np.int64)
    attack = _count(g, n, fam >= 0)
    provoked = _count(g, n, truth.effect[row] == EFFECTS.index("provoked"))
    truth_cols: dict[str, np.ndarray] = {"attack_packets": attack, "attack_fraction": attack / total,
                                         "provoked_packets": provoked}
    bits = np.zeros(n, dtype=np.int64)
    for k, f in enumerate(FAMILIES):
        truth_cols[ATTACK_PACKET_COLUMNS[k]] = _count(g, n, fam == k)
        bits |= (truth_cols[ATTACK_PACKET_COLUMNS[k]] > 0).astype(np.int64) << k
    names, sources = {}, {}
    for c in np.unique(bits).tolist():
        fams = [f for k, f in enumerate(FAMILIES) if c >> k & 1]
        names[c] = class_name(fams)
        used = {family(f).label_source for f in fams}
        sources[c] = "+".join(s for s in SOURCES if s in used) or "none"

    node = groups // n_win if n else np.zeros(0, dtype=np.int64)
    out = pd.DataFrame({
        "host": np.asarray([nd.name for nd in plan.nodes], dtype=object)[node],
        "host_ip": np.asarray([nd.ip for nd in plan.nodes], dtype=object)[node],
        "window": (groups % n_win).astype(np.int64) if n else np.zeros(0, dtype=np.int64),
        "first_ts": ns_to_s(first_ns), "last_ts": ns_to_s(last_ns), "first_ts_ns": first_ns,
        "packets": total,
    })  # fmt: skip
    out = pd.concat([out, pd.DataFrame(cols)], axis=1)
    for c, v in truth_cols.items():
        out[c] = v
    for k, f in enumerate(FAMILIES):
        out[f"label_{f}"] = (bits >> k & 1).astype(bool)
    out["label"] = pd.Series(bits).map(names).to_numpy(dtype=object)
    out["label_source"] = pd.Series(bits).map(sources).to_numpy(dtype=object)
    return out


def episode_rule_text() -> str:
    """The label rule of the episode view, for the dataset card."""
    return ("window-host: an episode (plan node, plan window) carries family F when at least one packet the "
            "node sent or received in the window (its 5-tuple flows' observations, one capture point each) "
            "has an effect caused by an attack of F")
