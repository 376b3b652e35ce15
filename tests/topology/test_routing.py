import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from uavcas.topology.routing import (
    USABLE_LOSS_MAX,
    Topology,
    etx,
    nearest_neighbour_topology,
    route,
    with_wormholes,
)


def _every_component_has_a_bs(edges, is_bs: np.ndarray) -> bool:
    """Independent oracle: flood-fill from every base station over `edges`; every node is reached."""
    adj: dict[int, set[int]] = {i: set() for i in range(len(is_bs))}
    for i, j in edges:
        adj[i].add(j)
        adj[j].add(i)
    seen = set(np.flatnonzero(is_bs).tolist())
    todo = list(seen)
    while todo:
        for nb in adj[todo.pop()] - seen:
            seen.add(nb)
            todo.append(nb)
    return len(seen) == len(is_bs)


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
    assert _every_component_has_a_bs(topo.edges, is_bs)
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
    for u in range(n_uav):
        p = route(topo, n, u, n_uav + u % n_bs)
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


def _loss_by_distance(pos, is_bs, reach_m):
    """A loss matrix: 0 within reach_m, 1 beyond (BS-BS pairs are wired anyway)."""
    d = np.linalg.norm(pos[:, None] - pos[None], axis=-1)
    loss = np.where(d <= reach_m, 0.0, 1.0)
    np.fill_diagonal(loss, 0.0)
    return loss


@settings(max_examples=150, deadline=None)
@given(st.integers(0, 10**6), st.integers(1, 40), st.integers(1, 3), st.floats(80.0, 600.0))
def test_quality_routing_never_uses_a_dead_link_and_marks_stranded_uavs(seed, n_uav, n_bs, reach_m):
    pos, is_bs = _swarm(seed, n_uav, n_bs)
    loss = _loss_by_distance(pos, is_bs, reach_m)
    topo = nearest_neighbour_topology(pos, is_bs, loss)
    n = len(pos)
    for (i, j), why in zip(topo.edges, topo.reasons):
        assert why == "backhaul" or loss[i, j] < USABLE_LOSS_MAX
    d = np.linalg.norm(pos[:, None] - pos[None], axis=-1)
    for u in range(n_uav):  # nearest *usable* peer
        ok = np.flatnonzero((loss[u] < USABLE_LOSS_MAX) & (np.arange(n) != u))
        if ok.size:
            assert tuple(sorted((u, int(ok[np.argmin(d[u, ok])])))) in topo.edges
    # disconnected exactly when no usable multi-hop path to a BS exists at all
    usable = (loss < USABLE_LOSS_MAX) | np.outer(is_bs, is_bs)
    np.fill_diagonal(usable, False)
    reach = is_bs.copy()
    while True:
        more = reach | (usable[:, reach].any(axis=1))
        if (more == reach).all():
            break
        reach = more
    assert set(topo.disconnected) == set(np.flatnonzero(~reach & ~is_bs).tolist())
    for u in range(n_uav):
        hops = route(topo, n, u, n_uav + u % n_bs)
        assert (hops is None) == (u in topo.disconnected)
        if hops is not None:
            assert all(loss[a, b] < USABLE_LOSS_MAX or (is_bs[a] and is_bs[b]) for a, b in zip(hops, hops[1:]))


def test_bridge_takes_the_best_path_not_the_nearest_bs():
    # UAV 0-1 are a pair far out; 0 is nearer BS 3 but that link is dead; 1 reaches BS 2
    pos = np.array([[900.0, 900, 50], [905.0, 900, 50], [0.0, 0, 25], [950.0, 990, 25]])
    is_bs = np.array([False, False, True, True])
    loss = np.zeros((4, 4))
    loss[0, 3] = loss[3, 0] = 1.0
    loss[1, 3] = loss[3, 1] = 0.5
    topo = nearest_neighbour_topology(pos, is_bs, loss)
    assert dict(zip(topo.edges, topo.reasons)) == {(0, 1): "nearest", (0, 2): "bridge", (2, 3): "backhaul"}
    assert topo.disconnected == ()
    loss[0, 2] = loss[2, 0] = loss[1, 2] = loss[2, 1] = 1.0
    assert nearest_neighbour_topology(pos, is_bs, loss).disconnected == (0, 1)


def test_routes_prefer_fewer_expected_transmissions_then_lower_indices():
    edges = ((0, 1), (0, 2), (1, 3), (2, 3))
    clean_via_2 = Topology(edges, ("nearest",) * 4, costs=(1.2, 1.0, 1.2, 1.0))
    assert route(clean_via_2, 4, 0, 3) == [0, 2, 3]
    assert route(Topology(edges, ("nearest",) * 4), 4, 0, 3) == [0, 1, 3]  # equal cost: lower index
    assert route(Topology(((0, 1),), ("nearest",)), 4, 0, 3) is None
    assert etx(0.0) == 1.0 and np.isinf(etx(1.0)) and etx(0.5) == 4.0


def test_wormhole_detour_needs_usable_links_and_avoids_the_victim():
    pos, is_bs = _swarm(11, 10, 2)
    loss = np.zeros((12, 12))
    topo = nearest_neighbour_topology(pos, is_bs, loss)
    worm = with_wormholes(topo, pos, is_bs, [(2, 7, 10)], loss)
    (d,) = worm.detours
    assert d.path[:2] == (2, 7) and d.path[-1] == 10 and 2 not in d.path[1:]
    assert all(tuple(sorted(h)) in worm.edges for h in zip(d.path, d.path[1:]))
    # detour edges are never taken by ordinary routes
    assert all(route(worm, 12, u, 10 + u % 2) == route(topo, 12, u, 10 + u % 2) for u in range(10))
    loss[2, 7] = loss[7, 2] = 1.0  # the victim cannot hear the attacker: no detour this window
    assert with_wormholes(topo, pos, is_bs, [(2, 7, 10)], loss).detours == ()
    with pytest.raises(ValueError):
        with_wormholes(topo, pos, is_bs, [(3, 3, 10)])


def test_no_bs_is_refused():
    with pytest.raises(ValueError, match="base station"):
        nearest_neighbour_topology(np.zeros((3, 3)), np.zeros(3, bool))
