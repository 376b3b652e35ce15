"""Context features (`ctx_*` columns): what monitors at the switches see around a flow.

Per-flow statistics barely move under the stealth attacks (blackhole, wormhole, replay); their
signature is in the context: what happens to a host over a few seconds, and what one switch sees
that another does not. This module computes that context from the run's captures alone, at
extraction time (`uavcas.extract`), into the `schema.CONTEXT_FEATURES` columns, one value per flow.

Inputs, and nothing else: the packet table of every capture point (`PacketTable`) and the flows
assembled from it (`Flows`). Never the plan, the forwarding tables, the attack log, labels, run
identity or the run's t0: the function cannot see them. Addresses are grouping keys only (which
packets belong to one host); no address, port or capture-point name reaches a column.

Observational notions, learned from the captures:

* **transmission**: one IP packet seen at several switches (each switch captures the frames
  entering it). Observations with the same header fields a bridge cannot change
  (`follow.KEY_COLUMNS`: addresses, ports, protocol, IP id, TCP seq, flags, TTL, length), each
  within `MAX_HOP_S` of the previous, form one transmission; the k-th observation at a switch
  goes to the k-th transmission. Its *ingress* is the first switch that saw it, its *path
  length* the number of switches that did (delivered or not: a lost packet's path is how far it
  got), its *delay* the time from its first to its last observation (defined once two switches
  saw it). No forwarding table is used: a packet's path is what the switches saw.
* **home switch** of an address: the switch where most transmissions from that address entered
  the network (what a node's own switch knows of the hosts on its host port).
* **usual TTL** of an address: the most common TTL of its transmissions.
* **reached**: a transmission seen at the home switch of its destination (a destination that
  never sent anything has no known home: its packets count as reached).

Windows are `window_s` (5 s) bins of the capture clock, `floor(t / window_s)` of Unix time; a flow
belongs to the window of its first packet, a transmission to that of its first observation. A
host's *shift* compares a window with the median of the host's earlier windows (causal: nothing
later is used; the median so that a few attacked windows do not become the baseline). Column
definitions, and what a deployed node must observe for each: docs/formats.md.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pandas as pd

from uavcas.schema import (
    CONTEXT_FEATURES,
    CONTEXT_FLOW_SHIFTS,
    CONTEXT_HOST_METRICS,
    CONTEXT_HOST_SHIFTS,
    CONTEXT_PAIR_METRICS,
    CONTEXT_PAIR_SHIFTS,
)

from .assemble import Flows
from .packets import PacketTable
from .routes import RouteShifts, earlier_median, flow_route_context, route_shifts
from .transmissions import NS_PER_S, Transmissions, transmissions

CONTEXT_WINDOW_S = 5.0
TCP_FIN, TCP_SYN, TCP_ACK = 0x01, 0x02, 0x10
_BIG = np.iinfo(np.int64).max


def _count_repeats(cols: list[np.ndarray], mask: np.ndarray, g: np.ndarray, n: int) -> np.ndarray:
    """Per flow: rows (of `mask`) whose `cols` tuple repeats an earlier row's."""
    if not mask.any():
        return np.zeros(n)
    sub = np.stack([c[mask].astype(np.int64) for c in cols], 1)
    _, idx, cnt = np.unique(sub, axis=0, return_index=True, return_counts=True)
    extra = np.zeros(int(mask.sum()))
    extra[idx] = cnt - 1
    return np.bincount(g[mask], weights=extra, minlength=n)


def flow_context(p: PacketTable, fl: Flows, t: Transmissions) -> pd.DataFrame:
    """The per-flow context columns (`schema.CONTEXT_FLOW_FEATURES`), flow number order."""
    n = fl.n_flows
    r, g, fwd = fl.order, fl.flow, fl.fwd
    per = lambda v: np.bincount(g, weights=v, minlength=n) / np.maximum(np.bincount(g, minlength=n), 1)  # noqa: E731
    tx = t.tx[r]
    col = lambda name: np.asarray(p[name], dtype=np.int64)[r]  # noqa: E731
    flags, ttl, ip_id = col("tcp_flags"), col("ttl"), col("ip_id")
    seq, flen, ts = col("tcp_seq"), col("frame_len"), col("ts_ns")
    payload = col("ip_len") - col("ip_hdr_len") - col("l4_hdr_len")
    tcp = col("proto") == 6
    d = fwd.astype(np.int64)

    multi = t.n_points[tx] > 1
    n_multi = np.bincount(g, weights=multi, minlength=n)
    delay = np.bincount(g, weights=np.where(multi, t.delay_ms[tx], 0.0), minlength=n) / np.maximum(n_multi, 1)
    levels = np.zeros(n)
    if len(r):
        per_dir = np.unique(np.unique(np.stack([g, d, ttl], 1), axis=0)[:, :2], axis=0, return_counts=True)
        np.maximum.at(levels, per_dir[0][:, 0], per_dir[1] - 1)
    # near-duplicate: the direction, IP id, length and flags of an earlier packet of the flow with
    # another TCP seq or TTL: a copy re-sent with rewritten fields (a retransmission gets a new IP
    # id; a resent SYN-ACK keeps its seq and TTL)
    every = np.ones(len(r), dtype=bool)
    same = [g, d, ip_id, flen, flags]
    variants = _count_repeats(same, every, g, n) - _count_repeats(same + [seq, ttl], every, g, n)
    carries = tcp & ((payload > 0) | (flags & (TCP_SYN | TCP_FIN) > 0))
    retx = _count_repeats([g, d, seq, flen, flags, ttl], carries, g, n)
    size = np.maximum(np.bincount(g, minlength=n), 1)
    return pd.DataFrame({
        "ctx_path_len_mean": per(t.n_points[tx].astype(np.float64)),
        "ctx_delay_ms": np.where(n_multi > 0, delay, -1.0),
        "ctx_lost_frac": per(~t.reached[tx]),
        "ctx_offhome_frac": per(t.offhome[tx]),
        "ctx_ttl_off_frac": per(t.ttl_off[tx]),
        "ctx_ttl_levels": levels,
        "ctx_neardup_frac": variants / size,
        "ctx_retx_frac": retx / size,
        "ctx_seq_regress_frac": _seq_regressions(g, d, seq, payload, ts, carries, n) / size,
        "ctx_rtt_ms": handshake_rtt_ms(g, fwd, flags, tx, t, n),
    })


def _seq_regressions(g, d, seq, payload, ts, carries, n) -> np.ndarray:
    """Per flow: data-carrying TCP packets whose sequence number lies below the highest one sent
    before in their direction and repeats no earlier packet's (a stale copy, not a retransmission)."""
    if not carries.any():
        return np.zeros(n)
    f = pd.DataFrame({"g": g[carries], "d": d[carries], "seq": seq[carries], "len": payload[carries],
                      "t": ts[carries]}).sort_values(["g", "d", "t"], kind="stable")
    key = [f["g"], f["d"]]
    rel = (f["seq"] - f.groupby(key)["seq"].transform("first")) % (1 << 32)
    rel = rel.where(rel < (1 << 31), rel - (1 << 32))  # TCP sequence arithmetic is modulo 2^32
    prev_max = (rel + f["len"]).groupby(key).cummax().groupby(key).shift(1)
    stale = (rel < prev_max) & ~f.duplicated(["g", "d", "seq"], keep="first")
    return np.bincount(f["g"].to_numpy(), weights=stale.to_numpy(np.float64), minlength=n)


def handshake_rtt_ms(g, fwd, flags, tx, t: Transmissions, n) -> np.ndarray:
    """Per flow: the network's round trip of the handshake, ms: from the flow's first SYN entering
    the network (its first observation) to the last observation of the first SYN-ACK (the
    initiator's switch when it got there); -1 without both."""
    out = np.full(n, -1.0)
    syn = fwd & (flags & (TCP_SYN | TCP_ACK) == TCP_SYN)
    synack = ~fwd & (flags & (TCP_SYN | TCP_ACK) == (TCP_SYN | TCP_ACK))
    t_syn, t_sa = np.full(n, _BIG), np.full(n, _BIG)
    np.minimum.at(t_syn, g[syn], t.t_ns[tx[syn]])
    np.minimum.at(t_sa, g[synack], t.t_ns[tx[synack]])
    first_sa = np.full(n, -1, dtype=np.int64)
    is_first = synack & (t.t_ns[tx] == t_sa[g])
    first_sa[g[is_first]] = tx[is_first]
    ok = (t_syn < _BIG) & (first_sa >= 0)
    back = np.where(ok, t.t_last_ns[np.maximum(first_sa, 0)], 0)
    ok &= back >= t_syn
    out[ok] = (back[ok] - t_syn[ok]) / 1e6
    return out


def unanswered_requests(p: PacketTable, fl: Flows) -> np.ndarray:
    """Per flow: a request that got no answer at the capture point: no backward packet, and the
    flow opens with a TCP SYN or is not TCP (the lone ACK or FIN after a closed connection is no
    request)."""
    first = fl.first
    syn_open = (np.asarray(p["tcp_flags"])[first] & (TCP_SYN | TCP_ACK)) == TCP_SYN
    request = syn_open | (np.asarray(p["proto"])[first] != 6)
    return request & (np.bincount(fl.flow, weights=~fl.fwd, minlength=fl.n_flows) == 0)


@dataclass(frozen=True)
class Observed:
    """What the windows aggregate. Per flow: `ini`, `res` (address codes of its initiator and
    responder), `win`, `unanswered`, `rtt` (ms, NaN without a handshake). Per transmission:
    `win`, `path` and, over the ones seen at two switches or more, `delay` (NaN otherwise)."""

    ini: np.ndarray
    res: np.ndarray
    f_win: np.ndarray
    unanswered: np.ndarray
    rtt: np.ndarray
    t_win: np.ndarray
    path: np.ndarray
    delay: np.ndarray

    @staticmethod
    def of(p: PacketTable, fl: Flows, t: Transmissions, rtt_ms: np.ndarray, window_s: float) -> "Observed":
        w_ns = int(round(window_s * NS_PER_S))
        first = fl.first
        # the initiator (the flow's src) sent the first packet unless it went backward
        fwd_first = fl.first_sent_forward
        return Observed(
            ini=np.where(fwd_first, t.addr_src[first], t.addr_dst[first]),
            res=np.where(fwd_first, t.addr_dst[first], t.addr_src[first]),
            f_win=np.asarray(p["ts_ns"], dtype=np.int64)[first] // w_ns,
            unanswered=unanswered_requests(p, fl).astype(np.float64), rtt=np.where(rtt_ms >= 0, rtt_ms, np.nan),
            t_win=t.t_ns // w_ns, path=t.n_points.astype(np.float64),
            delay=np.where(t.n_points > 1, t.delay_ms, np.nan),
        )


def _finish(tab: pd.DataFrame, shifts: dict[str, str]) -> pd.DataFrame:
    """Sort by (key, window), add the shifts against the key's earlier windows and the earlier
    medians (`base_<metric>`); times without a measurement are -1, everything else missing 0."""
    tab = tab.reset_index().sort_values(["key", "win"], kind="stable").reset_index(drop=True)
    tab[["flow_share", "log_flows"]] = tab[["flow_share", "log_flows"]].fillna(0.0)
    for metric, shift in shifts.items():
        tab["base_" + metric] = earlier_median(tab, metric)
        tab[shift] = (tab[metric] - tab["base_" + metric]).fillna(0.0)
    for m in ("rtt_ms", "delay_ms"):
        tab[m] = tab[m].fillna(-1.0)
    # the earlier medians stay missing: a flow without history gets no shift
    rest = [c for c in tab.columns if not c.startswith("base_")]
    tab[rest] = tab[rest].fillna(0.0)
    return tab.set_index(["key", "win"])


def _flow_counts(flows: pd.DataFrame, f_win: np.ndarray) -> pd.DataFrame:
    """Per (key, window) of `flows` (columns key, win, u, rtt): `flow_share` (its flows over all
    flows started in the window, so that neither the swarm's size nor a flood's rate sets the
    scale), `log_flows` (log(1 + flows): its shift is the log ratio to the key's past),
    `unanswered_frac`, `rtt_ms`."""
    fa = flows.groupby(["key", "win"]).agg(n=("u", "size"), unanswered_frac=("u", "mean"), rtt_ms=("rtt", "median"))
    total = pd.Series(f_win).value_counts()
    fa["flow_share"] = fa["n"] / total.reindex(fa.index.get_level_values("win")).to_numpy()
    fa["log_flows"] = np.log1p(fa.pop("n"))
    return fa


def host_windows(o: Observed, t: Transmissions) -> pd.DataFrame:
    """Per (host, window): `schema.CONTEXT_HOST_METRICS` and their shifts (`CONTEXT_HOST_SHIFTS`).
    A flow counts for both its hosts, a transmission for its source and its destination."""
    twice = lambda a: np.r_[a, a]  # noqa: E731
    flows = pd.DataFrame({"key": np.r_[o.ini, o.res], "win": twice(o.f_win), "u": twice(o.unanswered),
                          "rtt": twice(o.rtt)})
    fa = _flow_counts(flows, o.f_win)
    ntx = t.src.shape[0]
    txs = pd.DataFrame({
        "key": np.r_[t.src, t.dst], "win": twice(o.t_win), "out": np.r_[np.ones(ntx), np.zeros(ntx)],
        "lost": twice(~t.reached).astype(np.float64), "offhome": twice(t.offhome).astype(np.float64),
        "ttl_off": twice(t.ttl_off).astype(np.float64), "path": twice(o.path), "delay": twice(o.delay),
    })
    txs["lost_out"] = txs["lost"].where(txs["out"] == 1)
    txs["lost_in"] = txs["lost"].where(txs["out"] == 0)
    ta = txs.groupby(["key", "win"]).agg(
        out_share=("out", "mean"), lost_out_frac=("lost_out", "mean"), lost_in_frac=("lost_in", "mean"),
        offhome_frac=("offhome", "mean"), ttl_off_frac=("ttl_off", "mean"), path_len_mean=("path", "mean"),
        delay_ms=("delay", "median"))
    return _finish(fa.join(ta, how="outer"), CONTEXT_HOST_SHIFTS)


def pair_windows(o: Observed, t: Transmissions) -> tuple[pd.DataFrame, np.ndarray]:
    """Per (unordered host pair, window): `schema.CONTEXT_PAIR_METRICS` and their shifts
    (`CONTEXT_PAIR_SHIFTS`); and each flow's pair code."""
    n = int(max(o.ini.max(initial=0), o.res.max(initial=0), t.src.max(initial=0), t.dst.max(initial=0))) + 1
    code = lambda a, b: np.minimum(a, b) * n + np.maximum(a, b)  # noqa: E731
    flows = pd.DataFrame({"key": code(o.ini, o.res), "win": o.f_win, "u": o.unanswered, "rtt": o.rtt})
    fa = _flow_counts(flows, o.f_win)
    txs = pd.DataFrame({"key": code(t.src, t.dst), "win": o.t_win, "lost": (~t.reached).astype(np.float64),
                        "path": o.path, "delay": o.delay})
    ta = txs.groupby(["key", "win"]).agg(lost_frac=("lost", "mean"), path_len_mean=("path", "mean"),
                                         delay_ms=("delay", "median"))
    tab = _finish(fa.join(ta, how="outer"), CONTEXT_PAIR_SHIFTS)
    return tab, code(o.ini, o.res)


def network_windows(o: Observed, t: Transmissions) -> pd.DataFrame:
    """Per window, over every host: share of transmissions lost, mean path length, share of
    requests unanswered."""
    tw = pd.DataFrame({"win": o.t_win, "lost": ~t.reached, "path": o.path})
    return pd.DataFrame({
        "ctx_net_lost_frac": tw.groupby("win")["lost"].mean(),
        "ctx_net_path_len_mean": tw.groupby("win")["path"].mean(),
        "ctx_net_unanswered_frac": pd.Series(o.unanswered).groupby(o.f_win).mean(),
    }).fillna(0.0)


def _take(tab: pd.DataFrame, key: np.ndarray, win: np.ndarray, cols: list[str]) -> np.ndarray:
    # every flow's (key, window) exists: the flow itself put it there
    return tab.reindex(pd.MultiIndex.from_arrays([key, win]))[cols].to_numpy()


@dataclass(frozen=True)
class PacketRoutes:
    """Per packet-table row, its transmission (`tx`); per transmission, its route shifts
    (`flows.routes`): what the episode view summarises over a host's own packets."""

    tx: np.ndarray
    shifts: RouteShifts


def context_frame(p: PacketTable, fl: Flows, window_s: float = CONTEXT_WINDOW_S) -> pd.DataFrame:
    """The `schema.CONTEXT_FEATURES` of every flow of `fl` (rows in flow number order), from the
    packet table of all capture points `p` that `fl` was assembled from."""
    return context_frames(p, fl, window_s)[0]


def context_frames(p: PacketTable, fl: Flows, window_s: float = CONTEXT_WINDOW_S) -> tuple[pd.DataFrame, PacketRoutes]:
    """`context_frame`, and the packets' route shifts (`PacketRoutes`) it was computed with."""
    if not window_s > 0:
        raise ValueError(f"context window must be > 0 s, got {window_s}")
    t = transmissions(p)
    shifts = route_shifts(p, t, window_s)
    routes = PacketRoutes(t.tx, shifts)
    if fl.n_flows == 0:
        return pd.DataFrame({c: np.zeros(0) for c in CONTEXT_FEATURES}), routes
    per_flow = flow_context(p, fl, t)
    o = Observed.of(p, fl, t, per_flow["ctx_rtt_ms"].to_numpy(), window_s)
    out = [per_flow]
    hw = host_windows(o, t)
    cols = list(CONTEXT_HOST_METRICS) + list(CONTEXT_HOST_SHIFTS.values())
    for role, host in (("src", o.ini), ("dst", o.res)):
        out.append(pd.DataFrame(_take(hw, host, o.f_win, cols), columns=[f"ctx_{role}_{c}" for c in cols]))
    pw, pair = pair_windows(o, t)
    cols = list(CONTEXT_PAIR_METRICS) + list(CONTEXT_PAIR_SHIFTS.values())
    out.append(pd.DataFrame(_take(pw, pair, o.f_win, cols), columns=[f"ctx_pair_{c}" for c in cols]))
    # the flow's own round trip, delay and path against its host pair's earlier windows
    base = _take(pw, pair, o.f_win, ["base_rtt_ms", "base_delay_ms", "base_path_len_mean"])
    own = np.stack([o.rtt, np.where(per_flow["ctx_delay_ms"] > 0, per_flow["ctx_delay_ms"], np.nan),
                    np.where(per_flow["ctx_path_len_mean"] > 0, per_flow["ctx_path_len_mean"], np.nan)], 1)
    out.append(pd.DataFrame(np.nan_to_num(own - base, nan=0.0), columns=list(CONTEXT_FLOW_SHIFTS)))
    out.append(network_windows(o, t).reindex(o.f_win).fillna(0.0).reset_index(drop=True))
    out.append(flow_route_context(p, fl, t, shifts, window_s))
    frame = pd.concat(out, axis=1)
    if tuple(frame.columns) != CONTEXT_FEATURES:
        raise AssertionError(f"context columns {list(frame.columns)} differ from schema.CONTEXT_FEATURES")
    return frame.astype(np.float64), routes
