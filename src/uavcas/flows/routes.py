"""Observed routes: which switches a host pair's packets cross, and when that changed.

A wormhole adds a hop and its delay to the victim's path and moves its traffic through the
attacker's switch. What a flow's own first window shows (`flows.context`) misses it when the flow
is a long stream (a MAVLink link, a video) that began before the attack, and a moving swarm's
routes change every plan window anyway, so "another route than before" says little. This module
looks at every transmission when it crossed the network:

* **route** of a transmission: the ordered sequence of the switches that saw it (its ingress
  first), as one integer code. Exact while (switches + 1) ** (path length) < 2**64 (a 20-switch
  network up to 14 switches on a path); past that the code wraps and two long routes can share a
  code, which can only hide a change, never invent one.
* **route change** of a directed host pair: the modal route of its delivered transmissions in a
  `ROUTE_BIN_S` bin differs from the one of its previous bin with one. The twin re-plans the
  whole network's forwarding at once when the swarm moves (at each plan window, which the
  captures do not know), so many pairs change together; a detour installed for one victim
  changes a few pairs at a moment when the rest of the network keeps its routes. A change is
  *lonely* when the share of the network's pairs that changed in its bin or the bin before is
  below `LONELY_SHARE`, or when all of those pairs join the same two home switches (a detour in a
  small swarm: its 2 pairs are a large share of few).
* per transmission: `lonely` (1 when its pair's last route change, at or before its bin, was
  lonely; 0 otherwise or before any change), `path_shift` (switches that saw it less the median
  over the pair's earlier context windows of their mean path length) and `delay_shift_ms`
  (first-to-last observation time less the median of the earlier windows' median delay; NaN
  when one switch saw it or the pair has no earlier window), `off_own` (`off_own_route`: a
  switch it crossed sent it another way than it sent the other kind, its own or passing traffic,
  to the same destination or, failing that, toward the base stations), `off_passing` (the same,
  counted only where it was passing traffic) and `lonely_off` (off its switches' own routes while
  on a lonely route).

Measured (1 s bins): a plan window's re-planning changed 25-100 % of the pairs seen in a 10-UAV
and two 6-UAV runs; a wormhole's start changed 1 of 19 pairs (5 %) in the first and 2 of 12
(17 %) in a 6-UAV run. "Another route than the pair's usual one" instead flagged about half of
the Benign packets of the 10-UAV run, whose routes change every plan window.

Measured on the medium campaign's captures (1 s bins): in `ddos=1000+wormhole` run 10 a comparison
could be made for 58 % of the detoured transmissions and 53 % of the Benign ones; the switch
disagreed for every detoured one in 7 of the 11 plan windows holding some (0-16 % in the others),
and for 0-39 % of the Benign ones by window: in the wormhole's windows the Benign packets the
victim's and the base station's switches relay disagree with their own detoured ones. In the
`wormhole` run 4 only 1.6 % of the detoured transmissions could be compared (no other traffic
crossed the switches on the detour toward the same destination), so the column was silent there;
compared toward any base station, all 10 of that run's disagreeing (window, switch) cells are a
wormhole's (stop 30).

Windows and bins are the context's: `floor(t / length)` of the capture clock, a transmission in
the one of its first observation. Nothing but the captures is read (no plan, forwarding table or
attack log); addresses only group packets.
"""

from __future__ import annotations

import re
from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
import pandas as pd

from .follow import node_of_point

if TYPE_CHECKING:
    from .assemble import Flows
    from .packets import PacketTable
    from .transmissions import Transmissions

_NS = 1_000_000_000
ROUTE_BIN_S = 1.0  # short against a plan window (5 s), long against a stream's packet spacing
LONELY_SHARE = 0.2  # re-planned windows changed >= 25 % of pairs in the runs measured; one detour 5-17 %
# the other kind's packets at a switch: streams send every 10-200 ms, and a plan window (5 s) is far longer
OWN_MATCH_S = 0.5
BS_NODE = re.compile(r"bs\d+")  # a base station's node name (`twin.plan`), its switch's point s-bs<k>


def earlier_median(tab: pd.DataFrame, metric: str) -> pd.Series:
    """Median of the key's earlier windows that had a value (NaN in its first one). `tab` is
    sorted by (key, window).

    pandas' grouped expanding median runs in one compiled pass over all keys; a per-key
    `transform(lambda ...)` built a Series per key and took 29 of the 35 s of a 2,400-flow
    synthetic dataset's context columns (tests/flows/test_flows_routes.py pins the two equal)."""
    vals = pd.Series(tab[metric].to_numpy(dtype=float), index=pd.RangeIndex(len(tab)))
    key = pd.Series(tab["key"].to_numpy(), index=vals.index)
    med = vals.groupby(key, sort=False).expanding().median().droplevel(0).sort_index()
    earlier = med.groupby(key).shift(1).groupby(key).ffill()
    return pd.Series(earlier.to_numpy(), index=tab.index, name=metric)


def modal_by(frame: pd.DataFrame, keys: list[str], value: str) -> pd.DataFrame:
    """Per group of `keys`, its most frequent `value` (ties to the smaller): one row per group,
    columns `keys` and `value`, sorted by `keys`."""
    counts = frame[keys + [value]].value_counts().rename("_count").reset_index()
    counts = counts.sort_values(keys + ["_count", value], ascending=[True] * len(keys) + [False, True], kind="stable")
    return counts.drop_duplicates(keys)[keys + [value]].reset_index(drop=True)


def route_matrix(p: "PacketTable", t: "Transmissions") -> np.ndarray:
    """Per transmission, the capture points that saw it in crossing order (its ingress first), padded
    with -1 to the longest route: shape (transmissions, longest path)."""
    n_tx = t.n_points.shape[0]
    if not n_tx:
        return np.zeros((0, 0), dtype=np.int64)
    ts = np.asarray(p["ts_ns"], dtype=np.int64)
    point = np.asarray(p["point"], dtype=np.int64)
    order = np.lexsort((ts, t.tx))  # by transmission, then time: the switches in crossing order
    starts = np.r_[0, np.cumsum(t.n_points)[:-1]]
    rank = np.arange(order.shape[0]) - np.repeat(starts, t.n_points)
    out = np.full((n_tx, int(t.n_points.max())), -1, dtype=np.int64)
    out[t.tx[order], rank] = point[order]
    return out


def route_codes(routes: np.ndarray) -> np.ndarray:
    """Per transmission: the code of its ordered switch sequence (`route_matrix`; module docstring)."""
    if not routes.size:
        return np.zeros(routes.shape[0], dtype=np.uint64)
    base = np.uint64(int(routes.max()) + 2)
    with np.errstate(over="ignore"):  # wraps past 64 bits (docstring)
        weight = np.cumprod(np.r_[np.uint64(1), np.full(routes.shape[1] - 1, base, dtype=np.uint64)])
        terms = (routes + 1).astype(np.uint64) * weight  # padding (-1) adds 0
    return terms.sum(axis=1, dtype=np.uint64)


def base_station_points(points: Sequence[str]) -> np.ndarray:
    """Per capture point: True for a base station's switch (named s-bs<k>, docs/formats.md)."""
    return np.array([BS_NODE.fullmatch(node_of_point(name) or "") is not None for name in points], dtype=bool)


def off_own_route(routes: np.ndarray, t: "Transmissions", base_station: np.ndarray,
                  match_s: float = OWN_MATCH_S) -> tuple[np.ndarray, np.ndarray]:
    """Per transmission, (any, passing): 1.0 when a switch it crossed sent it to another next switch
    than the nearest packet in time (within `match_s`) of the other kind that the switch sent
    toward the same destination, its own traffic against passing traffic; 0.0 when every such
    comparison agrees, NaN when none can be made. `any` counts it at every switch it crossed,
    `passing` only where it was passing traffic.

    Planned routes share their suffixes (a relay forwards a passing packet as it forwards its
    own); a wormhole's detour takes only the victim's traffic with its base station another way:
    at the attacker's switch the victim's packets pass straight to the base station that the
    attacker's own reach another way, and at the victim's and the base station's switches their
    own packets to each other leave another way than the ones they relay.

    Where the switch sent nothing of the other kind to that destination in time, and the
    destination is at a base station (`base_station`: per capture point, `base_station_points`),
    the comparison is with the other kind's traffic toward any base station: the base stations
    are wired to each other, and a UAV reaches them all through its uplink. An attacker's own
    telemetry goes to its own base station, rarely to the victim's: compared by exact destination
    only, the detours of the medium campaign's wormhole runs were mostly not comparable (docs/
    measurements.md, stop 30). The nearest packet rather than a bin's most frequent next switch:
    a re-planned network's bin holds both its old and its new routes."""
    n_tx = routes.shape[0]
    any_, passing = np.full(n_tx, np.nan), np.full(n_tx, np.nan)
    if n_tx == 0 or routes.shape[1] < 2:
        return any_, passing
    # the destination's home switch; for an address that never sent, the switch its packet reached last
    dst_at = np.where(t.home[t.dst] >= 0, t.home[t.dst], routes[np.arange(n_tx), t.n_points - 1])
    to_bs = base_station[dst_at]
    hops = []
    for i in range(routes.shape[1] - 1):
        tx = np.flatnonzero(routes[:, i + 1] >= 0)
        if not tx.shape[0]:
            break
        # own: the source's first switch is its home; passing: any later switch (a packet entering
        # away from its source's home, a spoofed one, is neither at its first switch)
        kind = np.ones(tx.shape[0], dtype=np.int64) if i else np.where(routes[tx, 0] == t.home[t.src[tx]], 0, -1)
        hops.append(pd.DataFrame({"tx": tx, "ts": t.t_ns[tx], "x": routes[tx, i], "d": t.dst[tx],
                                  "to_bs": to_bs[tx], "n": routes[tx, i + 1], "kind": kind}))
    h = pd.concat(hops, ignore_index=True)
    h = h[h["kind"] >= 0].sort_values("ts", kind="stable")
    tol = int(round(match_s * _NS))
    for k in (0, 1):
        mine, other = h[h["kind"] == k], h[h["kind"] != k].rename(columns={"n": "n_other"})
        if mine.empty or other.empty:
            continue
        got = pd.merge_asof(mine, other[["ts", "x", "d", "n_other"]], on="ts", by=["x", "d"],
                            direction="nearest", tolerance=tol)["n_other"].to_numpy(dtype=np.float64, copy=True)
        miss = np.isnan(got) & mine["to_bs"].to_numpy()
        if miss.any():
            toward = other[other["to_bs"]]
            if not toward.empty:
                got[miss] = pd.merge_asof(mine[miss], toward[["ts", "x", "n_other"]], on="ts", by="x",
                                          direction="nearest", tolerance=tol)["n_other"].to_numpy()
        ok = np.isfinite(got)
        tx, off = mine["tx"].to_numpy()[ok], (mine["n"].to_numpy()[ok] != got[ok]).astype(np.float64)
        # a disagreement outweighs an agreement of the same packet; fmax lets a comparison replace NaN
        np.fmax.at(any_, tx, off)
        if k == 1:
            np.fmax.at(passing, tx, off)
    return any_, passing


@dataclass(frozen=True)
class RouteShifts:
    """Per transmission (float64; NaN where undefined): `lonely`, `path_shift`, `delay_shift_ms`,
    `off_own` and `off_passing` (`off_own_route`'s two), `lonely_off` (`off_own` where the
    transmission is on a lonely route, 0 where it is not: a detour's own signature, its pair
    moved alone and onto hops the switches' other traffic does not take)."""

    lonely: np.ndarray
    path_shift: np.ndarray
    delay_shift_ms: np.ndarray
    off_own: np.ndarray
    off_passing: np.ndarray
    lonely_off: np.ndarray


def lonely_routes(pair: np.ndarray, bin_: np.ndarray, code: np.ndarray, delivered: np.ndarray,
                  ends: np.ndarray | None = None, lonely_share: float = LONELY_SHARE) -> np.ndarray:
    """Per transmission: 1.0 when its pair's last route change at or before its bin was lonely.
    `ends` (per transmission, constant per pair): its two ends' home switches as one unordered
    code; a change is also lonely when every pair that changed in its bin or the one before joins
    the same two switches (one detour moves a victim's traffic with its base station both ways,
    2 pairs or a few more, which in a 5-UAV swarm is 20 % of the pairs and more)."""
    d = pd.DataFrame({"pair": pair[delivered], "bin": bin_[delivered], "code": code[delivered]})
    if d.empty:
        return np.zeros(pair.shape[0])
    modal = modal_by(d, ["pair", "bin"], "code")  # the modal route per (pair, bin)
    prev = modal.groupby("pair")["code"].shift(1)
    seen = prev.notna()
    changed = seen & (modal["code"] != prev)

    # the network's share of pairs changing in this bin or the one before: a re-planned network's
    # stragglers (pairs whose change fell late in a bin show it one bin later) are not lonely
    def this_or_last(rows: pd.DataFrame) -> pd.DataFrame:
        return pd.concat([rows, rows.assign(bin=rows["bin"] + 1)]).drop_duplicates()

    moved = this_or_last(modal.loc[changed, ["pair", "bin"]]).groupby("bin").size()
    known = this_or_last(modal.loc[seen, ["pair", "bin"]]).groupby("bin").size()
    share = (moved.reindex(known.index, fill_value=0) / known).reindex(modal["bin"]).to_numpy()
    lonely_change = changed & (share < lonely_share)
    if ends is not None:
        end_of = pd.Series(ends).groupby(pair).first()
        moved_ends = this_or_last(pd.DataFrame({"bin": modal.loc[changed, "bin"],
                                                "ends": end_of.reindex(modal.loc[changed, "pair"]).to_numpy()}))
        one_link = (moved_ends.groupby("bin")["ends"].nunique() == 1).reindex(modal["bin"]).fillna(False).to_numpy()
        lonely_change |= changed & one_link
    last = pd.Series(np.where(changed, lonely_change.astype(np.float64), np.nan))
    state = last.groupby(modal["pair"]).ffill().fillna(0.0)
    # every transmission takes the state of its pair's last bin with a delivered one, at or before its own
    tab = pd.DataFrame({"pair": modal["pair"], "bin": modal["bin"], "state": state})
    q = pd.DataFrame({"pair": pair, "bin": bin_, "i": np.arange(pair.shape[0])}).sort_values("bin", kind="stable")
    got = pd.merge_asof(q, tab.sort_values("bin", kind="stable"), on="bin", by="pair", direction="backward")
    out = np.zeros(pair.shape[0])
    out[got["i"].to_numpy()] = got["state"].fillna(0.0).to_numpy()
    return out


def route_shifts(p: "PacketTable", t: "Transmissions", window_s: float, bin_s: float = ROUTE_BIN_S) -> RouteShifts:
    """Each transmission against its directed host pair's routes (module docstring)."""
    if not t.n_points.shape[0]:
        empty = np.zeros(0)
        return RouteShifts(empty, empty, empty, empty, empty, empty)
    n_addr = int(max(t.src.max(), t.dst.max())) + 1
    pair = t.src * n_addr + t.dst
    routes = route_matrix(p, t)
    code = route_codes(routes).astype(np.int64)  # the same bits as int64: pandas groups them exactly
    bin_ = t.t_ns // int(round(bin_s * _NS))
    homes = np.sort(np.stack([t.home[t.src], t.home[t.dst]], 1), axis=1) + 1  # -1 (never sent) -> 0
    lonely = lonely_routes(pair, bin_, code, t.reached, ends=homes[:, 0] * (len(p.points) + 1) + homes[:, 1])

    win = t.t_ns // int(round(window_s * _NS))
    path = t.n_points.astype(np.float64)
    delay = np.where(t.n_points > 1, t.delay_ms, np.nan)
    tab = (pd.DataFrame({"key": pair, "win": win, "path": path, "delay": delay})
           .groupby(["key", "win"]).agg(path=("path", "mean"), delay=("delay", "median"))
           .reset_index().sort_values(["key", "win"], kind="stable").reset_index(drop=True))
    tab["base_path"] = earlier_median(tab, "path")
    tab["base_delay"] = earlier_median(tab, "delay")
    base = tab.set_index(["key", "win"])[["base_path", "base_delay"]].reindex(
        pd.MultiIndex.from_arrays([pair, win])).to_numpy()
    off, passing = off_own_route(routes, t, base_station_points(p.points))
    # lonely is 0 or 1 everywhere: the product is NaN exactly where no comparison was made
    return RouteShifts(lonely, path - base[:, 0], delay - base[:, 1], off, passing, off * lonely)


def _nanmean_by(group: np.ndarray, value: np.ndarray, n: int) -> np.ndarray:
    """Mean of the finite values per group; NaN where a group has none."""
    ok = np.isfinite(value)
    total = np.bincount(group[ok], weights=value[ok], minlength=n)
    count = np.bincount(group[ok], minlength=n)
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.where(count > 0, total / np.maximum(count, 1), np.nan)


def flow_route_context(p: "PacketTable", fl: "Flows", t: "Transmissions", shifts: RouteShifts,
                       window_s: float) -> pd.DataFrame:
    """Per flow (`schema.CONTEXT_ROUTE_FEATURES`): the share of its packets on a lonely route, and
    the largest per-window mean path and delay shift over the windows its packets crossed (0
    where undefined)."""
    n = fl.n_flows
    g, tx = fl.flow, t.tx[fl.order]
    win = np.asarray(p["ts_ns"], dtype=np.int64)[fl.order] // int(round(window_s * _NS))
    out = {"ctx_route_lonely_frac": np.nan_to_num(_nanmean_by(g, shifts.lonely[tx], n))}
    fw, fw_idx = np.unique(np.stack([g, win], 1), axis=0, return_inverse=True)
    fw_idx = fw_idx.reshape(-1)
    for name, value in (("ctx_path_len_shift_max", shifts.path_shift),
                        ("ctx_delay_shift_max_ms", shifts.delay_shift_ms)):
        per_window = _nanmean_by(fw_idx, value[tx], fw.shape[0])
        best = np.full(n, -np.inf)
        ok = np.isfinite(per_window)
        np.maximum.at(best, fw[ok, 0], per_window[ok])
        out[name] = np.where(np.isfinite(best), best, 0.0)
    return pd.DataFrame(out)


def episode_route_context(group: np.ndarray, rows_tx: np.ndarray, rows_peer: np.ndarray, shifts: RouteShifts,
                          n: int) -> dict[str, np.ndarray]:
    """Per episode (`schema.EPISODE_ROUTE_FEATURES`), over its packets (`group`: the episode of each,
    `rows_tx` its transmission, `rows_peer` the address at the other end): the mean lonely share,
    path shift and delay shift, and the largest of each over its peers' traffic (a base
    station's episode holds every UAV's packets, of which a wormhole moves one victim's); 0 where
    none is defined."""
    out = {name: np.nan_to_num(_nanmean_by(group, value[rows_tx], n)) for name, value in (
        ("ctx_pkt_route_lonely_frac", shifts.lonely), ("ctx_pkt_path_len_shift", shifts.path_shift),
        ("ctx_pkt_delay_shift_ms", shifts.delay_shift_ms), ("ctx_pkt_off_own_route_frac", shifts.off_own),
        ("ctx_pkt_passing_off_route_frac", shifts.off_passing), ("ctx_pkt_lonely_off_route_frac", shifts.lonely_off))}
    # per peer, then the largest: a base station's episode holds every UAV's packets, and a
    # wormhole detours one victim's; averaged over all peers its shift shrinks by their number
    pairs, inv = np.unique(np.stack([group, rows_peer], 1).reshape(-1, 2), axis=0, return_inverse=True)
    for name, value in (("ctx_pkt_route_lonely_max", shifts.lonely),
                        ("ctx_pkt_path_len_shift_peer_max", shifts.path_shift),
                        ("ctx_pkt_delay_shift_peer_max_ms", shifts.delay_shift_ms),
                        ("ctx_pkt_off_own_route_max", shifts.off_own),
                        ("ctx_pkt_passing_off_route_max", shifts.off_passing),
                        ("ctx_pkt_lonely_off_route_max", shifts.lonely_off)):
        per_peer = np.nan_to_num(_nanmean_by(inv.reshape(-1), value[rows_tx], pairs.shape[0]))
        best = np.full(n, -np.inf)
        np.maximum.at(best, pairs[:, 0], per_peer)
        out[name] = np.where(np.isfinite(best), best, 0.0)  # 0: an episode without packets
    return out
