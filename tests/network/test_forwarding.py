"""The L2 forwarding of a window: shortest-path trees per destination, routes, wormhole detours."""

from __future__ import annotations

import itertools
import random

import pytest

from uavcas.network.forwarding import Detour, adjacency, compute, shortest_path

NODES = ["uav0", "uav1", "uav2", "uav3", "bs0"]


def test_bfs_is_deterministic_and_prefers_plan_order():
    # square uav0-uav1-uav3 / uav0-uav2-uav3: two equal paths; the lower-index neighbour wins
    links = [("uav0", "uav1"), ("uav0", "uav2"), ("uav1", "uav3"), ("uav2", "uav3")]
    fwd = compute(NODES, links)
    assert fwd.path("uav0", "uav3") == ["uav0", "uav1", "uav3"]
    assert fwd.path("uav3", "uav0") == ["uav3", "uav1", "uav0"]
    assert compute(NODES, list(reversed(links))).next_hop == fwd.next_hop
    assert fwd.path("uav0", "bs0") is None and "bs0" not in fwd.next_hop["uav0"]


def test_routes_are_honoured_both_ways():
    links = [("uav0", "uav1"), ("uav0", "uav2"), ("uav1", "uav3"), ("uav2", "uav3")]
    fwd = compute(NODES, links, routes=[["uav0", "uav2", "uav3"]])
    assert fwd.path("uav0", "uav3") == ["uav0", "uav2", "uav3"]
    assert fwd.path("uav3", "uav0") == ["uav3", "uav2", "uav0"]
    assert not fwd.rejected


def test_wormhole_detours_victim_bs_both_ways_and_nothing_else():
    links = [("uav0", "bs0"), ("uav0", "uav1"), ("uav1", "bs0"), ("uav2", "uav0")]
    plain = compute(NODES, links)
    fwd = compute(NODES, links, wormholes=[("uav0", "uav1", "bs0")])
    assert fwd.detour_path("uav0", "bs0") == ["uav0", "uav1", "bs0"] and not fwd.rejected
    assert fwd.next_hop == plain.next_hop  # by destination MAC nothing moves: uav2 -> bs0 via uav0 direct
    assert fwd.path("uav2", "bs0") == ["uav2", "uav0", "bs0"]
    (d,) = fwd.detours
    assert d.alias_hops() == {("uav0", "uav0>bs0"): ("uav1", "uav0>bs0"), ("uav1", "uav0>bs0"): ("bs0", "uav0>bs0"),
                              ("bs0", "bs0>uav0"): ("uav1", "bs0>uav0"), ("uav1", "bs0>uav0"): ("uav0", "bs0>uav0")}


def test_detour_links_carry_only_the_detour():
    # uav1-bs0 exists for the detour only: uav1's own traffic keeps going through uav0
    links = [("uav0", "bs0"), ("uav0", "uav1"), ("uav1", "bs0")]
    fwd = compute(NODES, links, wormholes=[Detour("uav0", "uav1", "bs0", ("uav0", "uav1", "bs0"))],
                  detour_links=[("bs0", "uav1")])
    assert fwd.path("uav1", "bs0") == ["uav1", "uav0", "bs0"] and fwd.path("bs0", "uav1") == ["bs0", "uav0", "uav1"]
    assert fwd.detour_path("uav0", "bs0") == ["uav0", "uav1", "bs0"]


def test_impossible_override_is_rejected_not_looped():
    links = [("uav0", "bs0")]
    fwd = compute(NODES, links, wormholes=[("uav0", "uav1", "bs0")], routes=[["uav0", "uav3", "bs0"]])
    assert fwd.path("uav0", "bs0") == ["uav0", "bs0"] and fwd.detours == ()
    assert fwd.rejected == ["route uav0>uav3>bs0", "route bs0>uav3>uav0", "wormhole uav0>uav1>bs0"]
    bad_hops = compute(NODES, links + [("uav1", "bs0")],
                       wormholes=[Detour("uav0", "uav1", "bs0", ("uav0", "uav1", "bs0"))])
    assert bad_hops.detours == () and bad_hops.rejected == ["wormhole uav0>uav1>bs0"]  # uav0-uav1 is no link


@pytest.mark.parametrize("overrides", [False, True], ids=["plain", "overrides"])
@pytest.mark.parametrize("seed", range(20))
def test_random_windows_loop_free_and_shortest(seed, overrides):
    rng = random.Random(seed)
    nodes = [f"n{i}" for i in range(9)]
    links = [(a, b) for a, b in itertools.combinations(nodes, 2) if rng.random() < 0.3]
    routes = [[rng.choice(nodes) for _ in range(3)] for _ in range(3)] if overrides else []
    worm = [tuple(rng.sample(nodes, 3))] if overrides else []
    fwd = compute(nodes, links, routes=routes, wormholes=worm)
    adj = adjacency(nodes, links)
    for s, d in itertools.permutations(nodes, 2):
        p = fwd.path(s, d)
        sp = shortest_path(adj, s, d)
        assert (p is None) == (sp is None)  # reachable exactly when connected: no loops, no holes
        if p:
            assert all(b in adj[a] for a, b in zip(p, p[1:])) and len(set(p)) == len(p)
            if not routes:  # without routes every path is a shortest one (detours use alias MACs)
                assert len(p) == len(sp), (s, d, p, sp)
