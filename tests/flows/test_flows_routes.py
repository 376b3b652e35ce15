"""Observed routes (`uavcas.flows.routes`) on hand-built captures: a detour one pair takes alone is
lonely, a network that re-routes together is not, lost packets change no route, and a long stream
shows the hop and delay a detour added in a later window."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from helpers.capture_tables import HOP_S, send, table
from uavcas.flows.assemble import FlowConfig, assemble
from uavcas.flows.context import context_frame, context_frames
from uavcas.flows.routes import (
    RouteShifts,
    base_station_points,
    earlier_median,
    episode_route_context,
    off_own_route,
    route_codes,
    route_matrix,
)
from uavcas.flows.transmissions import transmissions
from uavcas.schema import CONTEXT_FEATURES, CONTEXT_ROUTE_FEATURES

STEP_S = 0.1  # packet spacing of every stream


def stream(src: str, dst: str, port: int, paths: list[tuple[float, list[str]]], until: float, id0: int) -> list[dict]:
    """A UDP stream src -> dst every STEP_S from 0 to `until`; `paths`: (from t, switches) in time order."""
    out = []
    for k, t in enumerate(np.arange(0.0, until, STEP_S)):
        path = [p for since, p in paths if since <= t][-1]
        out += send(round(float(t), 3), path, src, dst, sport=port, dport=port, proto=17, id=id0 + k, payload=50)
    return out


def frame(obs: list[dict]) -> pd.DataFrame:
    p = table(obs)
    fl = assemble(p, FlowConfig())
    c = context_frame(p, fl)
    first = fl.first
    c["src"] = np.asarray(p["src_lo"])[first]
    c["sport"] = np.asarray(p["sport"])[first]
    return c.set_index("sport")


def network(detour_at: float | None = None, everyone_at: float | None = None, until: float = 10.0,
            hosts: tuple[str, ...] = ("a", "b", "r", "x"), also: tuple[str, str] | None = None) -> list[dict]:
    """The 12 directed pairs of hosts a, b, r and x, each a stream on its direct link; a -> b and
    back may take the detour via r at `detour_at` (alone: 2 of 12 pairs), and so may the pair
    `also` via a third host, or every pair a route through another host at `everyone_at`."""
    obs: list[dict] = []
    pairs = [(s, d) for s in hosts for d in hosts if s != d]
    for k, (s, d) in enumerate(pairs):
        paths = [(0.0, [s, d])]
        if detour_at is not None and {s, d} == {"a", "b"}:
            paths.append((detour_at, [s, "r", d]))
        if detour_at is not None and also is not None and {s, d} == set(also):
            paths.append((detour_at, [s, next(h for h in hosts if h not in (s, d)), d]))
        if everyone_at is not None:
            paths.append((everyone_at, [s, next(h for h in hosts if h not in (s, d)), d]))
        obs += stream(s, d, PORT[(s, d)], paths, until, id0=10_000 * k)
    return obs


PORT = {(s, d): 1000 + 10 * "abrx".index(s) + "abrx".index(d) for s in "abrx" for d in "abrx" if s != d}


def test_a_detour_one_pair_takes_alone_is_lonely():
    c = frame(network(detour_at=5.3))
    # the detour began in the 1 s bin [5, 6): that bin's packets and the later ones, 50 of a -> b's
    # 100, are on a lonely route; the other pairs kept theirs
    ab, ba = PORT[("a", "b")], PORT[("b", "a")]
    assert c.loc[ab, "ctx_route_lonely_frac"] == pytest.approx(0.5)
    assert c.loc[ba, "ctx_route_lonely_frac"] == pytest.approx(0.5)
    assert (c.drop(index=[ab, ba])["ctx_route_lonely_frac"] == 0).all()


def test_a_detour_in_a_small_swarm_is_lonely_though_its_pairs_are_a_third_of_them():
    # a, b and r: 6 directed pairs, of which the detour moves 2 (33 %, above LONELY_SHARE); both
    # join a's and b's switches, and nothing else moved
    c = frame(network(detour_at=5.3, hosts=("a", "b", "r")))
    ab, ba = PORT[("a", "b")], PORT[("b", "a")]
    assert c.loc[ab, "ctx_route_lonely_frac"] == pytest.approx(0.5)
    assert c.loc[ba, "ctx_route_lonely_frac"] == pytest.approx(0.5)
    assert (c.drop(index=[ab, ba])["ctx_route_lonely_frac"] == 0).all()


def test_two_pairs_of_switches_changing_together_are_not_lonely_in_a_small_swarm():
    # a <-> b and r <-> x re-routed in the same bin: 4 of 12 pairs, between two pairs of switches
    c = frame(network(detour_at=5.3, also=("r", "x")))
    assert (c["ctx_route_lonely_frac"] == 0).all()


def test_a_network_that_re_routes_together_is_not_lonely():
    c = frame(network(everyone_at=5.3))
    assert (c["ctx_route_lonely_frac"] == 0).all()


def test_lost_packets_change_no_route():
    obs = network()
    # every fifth packet a -> b is lost after its first switch: a shorter sequence, not a new route
    obs = [o for o in obs if not (o["sport"] == PORT[("a", "b")] and o["at"] == "b" and o["id"] % 5 == 0)]
    assert (frame(obs)["ctx_route_lonely_frac"] == 0).all()


def test_a_long_stream_shows_the_hop_and_delay_a_detour_added_later():
    # a -> b over 15 s: direct in the first two context windows, through r in the third
    obs = stream("a", "b", 1001, [(0.0, ["a", "b"]), (10.0, ["a", "r", "b"])], 15.0, id0=0)
    c = frame(obs)
    assert c.loc[1001, "ctx_path_len_shift_max"] == pytest.approx(1.0)
    assert c.loc[1001, "ctx_delay_shift_max_ms"] == pytest.approx(HOP_S * 1e3, abs=1e-3)
    # the flow's first window alone (the older columns) saw nothing
    assert c.loc[1001, "ctx_path_len_shift"] == 0


def test_route_codes_tell_order_and_length_apart():
    obs = (send(0.0, ["a", "r", "b"], "a", "b", sport=1, dport=1, proto=17, id=1)
           + send(1.0, ["a", "x", "b"], "a", "b", sport=1, dport=1, proto=17, id=2)
           + send(2.0, ["a", "r"], "a", "b", sport=1, dport=1, proto=17, id=3)
           + send(3.0, ["a", "r", "b"], "a", "b", sport=1, dport=1, proto=17, id=4))
    p = table(obs)
    t = transmissions(p)
    codes = route_codes(route_matrix(p, t))[np.argsort(t.t_ns)]
    assert codes[0] == codes[3] and len({int(c) for c in codes[:3]}) == 3


def test_the_route_columns_are_part_of_the_context_and_nothing_else_moves():
    obs = network(detour_at=5.3)
    p = table(obs)
    fl = assemble(p, FlowConfig())
    c, routes = context_frames(p, fl)
    assert tuple(c.columns) == CONTEXT_FEATURES and set(CONTEXT_ROUTE_FEATURES) <= set(c.columns)
    assert routes.tx.shape[0] == len(p) and routes.shifts.lonely.shape[0] == int(routes.tx.max()) + 1
    # reversed row order: the same columns, flow by flow
    pd.testing.assert_frame_equal(frame(obs).sort_index(), frame(obs[::-1]).sort_index())


def test_episode_route_columns_take_the_largest_peer_mean_even_when_negative():
    """Episode 0: peer 7's packets shifted by +1 and +0 switches (mean 0.5), peer 8's by +0.1 twice:
    the mean over the episode is 0.3, the per-peer largest 0.5. Episode 1: every peer shortened
    (-1, -2): the largest is -1, not the 0 of "none defined". Episode 2: no finite shift, so 0."""
    path = np.array([1.0, 0.0, 0.1, 0.1, -1.0, -2.0, np.nan])
    delay = np.array([4.0, 0.0, 1.0, 1.0, -3.0, -5.0, np.nan])
    off = np.array([1.0, np.nan, 0.0, 0.0, 0.0, np.nan, np.nan])
    shifts = RouteShifts(lonely=np.array([1.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0]), path_shift=path,
                         delay_shift_ms=delay, off_own=off, off_passing=off, lonely_off=off * 0.5)
    group = np.array([0, 0, 0, 0, 1, 1, 2])
    peer = np.array([7, 7, 8, 8, 7, 8, 7])
    out = episode_route_context(group, np.arange(7), peer, shifts, 3)
    assert out["ctx_pkt_path_len_shift"] == pytest.approx([0.3, -1.5, 0.0])
    assert out["ctx_pkt_path_len_shift_peer_max"] == pytest.approx([0.5, -1.0, 0.0])
    assert out["ctx_pkt_delay_shift_peer_max_ms"] == pytest.approx([2.0, -3.0, 0.0])
    assert out["ctx_pkt_route_lonely_max"] == pytest.approx([1.0, 0.0, 0.0])
    # the off-own-route share counts only the packets where a comparison was made
    assert out["ctx_pkt_off_own_route_frac"] == pytest.approx([1 / 3, 0.0, 0.0])
    assert out["ctx_pkt_off_own_route_max"] == pytest.approx([1.0, 0.0, 0.0])
    assert out["ctx_pkt_passing_off_route_frac"] == pytest.approx([1 / 3, 0.0, 0.0])
    assert out["ctx_pkt_lonely_off_route_max"] == pytest.approx([0.5, 0.0, 0.0])
    # a packet row points at its transmission: two rows of one transmission count twice
    twice = episode_route_context(np.array([0, 0]), np.array([0, 0]), np.array([7, 7]), shifts, 1)
    assert twice["ctx_pkt_path_len_shift_peer_max"] == pytest.approx([1.0])


def offs_by_sport(obs: list[dict]) -> dict[int, tuple[np.ndarray, np.ndarray]]:
    """`off_own_route`'s (any, passing) per transmission, grouped by the packets' source port."""
    p = table(obs)
    t = transmissions(p)
    off, passing = off_own_route(route_matrix(p, t), t, base_station_points(p.points))
    sport = np.zeros(t.n_points.shape[0], dtype=np.int64)
    sport[t.tx] = np.asarray(p["sport"])
    return {int(s): (off[sport == s], passing[sport == s]) for s in np.unique(sport)}


def test_a_relay_that_forwards_a_victim_away_from_its_own_route_is_seen():
    """r passes a's packets to b straight on while r's own packets to b go through x (a wormhole at
    r): both kinds disagree at r. x passes r's packets to b as it sends its own (a planned relay):
    x's own agree. A hop with nothing of the other kind to the same destination there (a -> x
    through r, with no own traffic of r to x; a's own first hops, with no passing traffic of a) is
    undefined."""
    obs = []
    for k in range(20):
        t0 = 0.04 * k
        obs += send(t0, ["a", "r", "b"], "a", "b", sport=1, dport=1, proto=17, id=100 + k)
        obs += send(t0 + 0.005, ["r", "x", "b"], "r", "b", sport=2, dport=1, proto=17, id=200 + k)
        obs += send(t0 + 0.010, ["x", "b"], "x", "b", sport=3, dport=1, proto=17, id=300 + k)
        obs += send(t0 + 0.015, ["a", "r", "x"], "a", "x", sport=4, dport=1, proto=17, id=400 + k)
    by = {sport: off for sport, (off, _) in offs_by_sport(obs).items()}
    assert by[1].shape == (20,) and np.all(by[1] == 1.0) and np.all(by[2] == 1.0)
    assert np.all(by[3] == 0.0) and np.isnan(by[4]).all()


def test_an_attacker_with_no_own_traffic_to_the_victims_base_station_is_compared_through_its_uplink():
    """r sends its own packets to base station bs0 through x; it passes a's packets to base station
    bs1 straight on (a wormhole at r). r sends nothing of its own to bs1, so only the base
    stations as one destination make a comparison: a's packets are off as passing traffic, r's
    own are off but never as passing traffic. a -> x through r (x is no base station, r sends
    nothing of its own to x) stays undefined."""
    obs = []
    for k in range(20):
        t0 = 0.04 * k
        obs += send(t0, ["a", "r", "bs1"], "a", "bs1", sport=1, dport=1, proto=17, id=100 + k)
        obs += send(t0 + 0.005, ["r", "x", "bs0"], "r", "bs0", sport=2, dport=1, proto=17, id=200 + k)
        obs += send(t0 + 0.010, ["a", "r", "x"], "a", "x", sport=4, dport=1, proto=17, id=400 + k)
    by = offs_by_sport(obs)
    assert np.all(by[1][0] == 1.0) and np.all(by[1][1] == 1.0)
    assert np.all(by[2][0] == 1.0) and np.isnan(by[2][1]).all()
    assert np.isnan(by[4][0]).all() and np.isnan(by[4][1]).all()
    # the same traffic between switches that are no base stations: nothing to compare
    rename = {"bs0": "b", "bs1": "x"}
    plain = offs_by_sport([{**o, "at": rename.get(o["at"], o["at"]), "dst": rename.get(o["dst"], o["dst"])}
                           for o in obs if o["sport"] != 4])
    assert np.isnan(plain[1][0]).all() and np.isnan(plain[2][0]).all()


def test_a_re_route_inside_a_bin_is_no_disagreement():
    """At t = 0.6 s, mid-bin, r's own packets to b and the ones it passes from a both go straight to
    b instead of through x. Most of r's own packets of the bin went through x, most passing ones
    straight: a bin's most frequent next switches disagree, each packet's nearest other agrees."""
    obs = []
    for k in range(25):
        t0 = round(0.04 * k, 3)
        obs += send(t0, ["r", "x", "b"] if t0 < 0.6 else ["r", "b"], "r", "b", sport=2, dport=1, proto=17, id=200 + k)
        if t0 >= 0.32:
            tp = round(t0 + 0.01, 3)
            obs += send(tp, ["a", "r", "x", "b"] if tp < 0.6 else ["a", "r", "b"], "a", "b", sport=1, dport=1,
                        proto=17, id=100 + k)
    by = offs_by_sport(obs)
    assert by[1][0].shape == (17,) and np.all(by[1][0] == 0.0)
    assert np.all(by[2][0][np.isfinite(by[2][0])] == 0.0)


@settings(max_examples=60, deadline=None)
@given(st.lists(st.tuples(st.integers(0, 6), st.one_of(st.none(), st.integers(0, 9))), min_size=1, max_size=60))
def test_earlier_median_is_the_median_of_the_keys_earlier_values(rows):
    """Per key (rows in window order), the median of its earlier non-missing values; NaN before any."""
    rows = sorted(rows, key=lambda r: r[0])  # grouped by key, order within a key kept
    tab = pd.DataFrame({"key": [f"k{k}" for k, _ in rows], "m": [np.nan if v is None else float(v) for _, v in rows]},
                       index=np.arange(len(rows))[::-1] + 5)  # an index that is neither 0.. nor sorted
    got = earlier_median(tab, "m")
    seen: dict[str, list[float]] = {}
    for (i, key), v in zip(tab["key"].items(), tab["m"]):
        prior = seen.setdefault(key, [])
        want = float(np.median(prior)) if prior else np.nan
        assert (np.isnan(got[i]) and np.isnan(want)) or got[i] == pytest.approx(want), (key, prior)
        if not np.isnan(v):
            prior.append(v)
