import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from uavcas.topology.routing import (
    is_connected_to_bs,
    nearest_neighbour_topology,
    route,
    shortest_path,
    with_wormholes,
)


def _swarm(seed: int, n_uav: int, n_bs: int):
    rng = np.random.default_rng(seed)
    uav = np.c_[rng.uniform(0, 1000, (n_uav, 2)), rng.uniform(30, 110, n_uav)]
    bs = np.c_[rng.uniform(0, 1000, (n_bs, 2)), np.full(n_bs, 25.0)]
    return np.vstack([uav, bs]), np.r_[np.zeros(n_uav, bool), np.ones(n_bs, bool)]


@settings(max_examples=200, deadline=None)
@given(st.integers(0, 10**6), st.integers(1, 60), st.integers(1, 4))
def test_every_uav_reaches_a_bs_and_links_its_nearest_peer(seed, n_uav, n_bs):
    pos, is_bs = _swarm(seed, n_uav, n_bs)
    topo = nearest_neighbour_topology(pos, is_bs)
    n = len(pos)
    assert is_connected_to_bs(topo, n, is_bs)
    assert list(topo.edges) == sorted(set(topo.edges)) and all(i < j for i, j in topo.edges)
    d = np.linalg.norm(pos[:, None] - pos[None], axis=-1)
    np.fill_diagonal(d, np.inf)
    edges = set(topo.edges)
    for u in range(n_uav):
        assert tuple(sorted((u, int(np.argmin(d[u]))))) in edges
    # one bridge per BS-less cluster: bridges never exceed the number of UAVs / 2
    assert sum(r == "bridge" for r in topo.reasons) <= max(1, n_uav // 2)
    # backhaul: a full mesh between base stations
    assert sum(r == "backhaul" for r in topo.reasons) == n_bs * (n_bs - 1) // 2
    adj = topo.adjacency(n)
    for u in range(n_uav):
        p = shortest_path(adj, u, n_uav + u % n_bs)
        assert p[0] == u and p[-1] == n_uav + u % n_bs
        assert all(tuple(sorted(h)) in edges for h in zip(p, p[1:]))


def test_bridge_joins_a_far_cluster_to_its_nearest_bs():
    # two UAVs close to each other, far from the BS: they are each other's nearest peer
    pos = np.array([[900.0, 900, 50], [905.0, 900, 50], [0.0, 0, 25], [100.0, 0, 25]])
    is_bs = np.array([False, False, True, True])
    topo = nearest_neighbour_topology(pos, is_bs)
    assert dict(zip(topo.edges, topo.reasons)) == {(0, 1): "nearest", (0, 3): "bridge", (2, 3): "backhaul"}


def _links(topo, names) -> dict[tuple[int, int], str]:
    """Links keyed by node identity (`names[i]` is node i's original index), not position in the input."""
    return {tuple(sorted((int(names[i]), int(names[j])))): r for (i, j), r in zip(topo.edges, topo.reasons)}


@settings(max_examples=50, deadline=None)
@given(st.integers(0, 10**6), st.integers(1, 30), st.integers(1, 4), st.randoms(use_true_random=False))
def test_routing_is_deterministic_regardless_of_input_order(seed, n_uav, n_bs, rnd):
    pos, is_bs = _swarm(seed, n_uav, n_bs)
    topo = nearest_neighbour_topology(pos, is_bs)
    assert topo == nearest_neighbour_topology(pos.copy(), is_bs.copy())
    # the same swarm listed in another order (BSs interleaved with UAVs) gives the same links
    perm = np.arange(len(pos))
    rnd.shuffle(perm)
    if np.array_equal(perm, np.arange(len(pos))):  # a shuffle may leave the order as it was
        perm = perm[::-1].copy()
    shuffled = nearest_neighbour_topology(pos[perm], is_bs[perm])
    assert _links(shuffled, perm) == _links(topo, np.arange(len(pos)))


def test_wormhole_detours_victim_bs_traffic_through_the_attacker():
    pos, is_bs = _swarm(11, 10, 2)
    topo = with_wormholes(nearest_neighbour_topology(pos, is_bs), pos, is_bs, [(2, 7)])
    n = len(pos)
    for bs in (10, 11):
        fwd = route(topo, n, 2, bs, is_bs)
        back = route(topo, n, bs, 2, is_bs)
        assert fwd[:2] == [2, 7] and back[-2:] == [7, 2] and fwd[-1] == bs
    assert (2, 7) in topo.edges and topo.overrides[0][:2] == (2, 7)
    with pytest.raises(ValueError):
        with_wormholes(topo, pos, is_bs, [(3, 3)])


def test_no_bs_is_refused():
    with pytest.raises(ValueError, match="base station"):
        nearest_neighbour_topology(np.zeros((3, 3)), np.zeros(3, bool))
