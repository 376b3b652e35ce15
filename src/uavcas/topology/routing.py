"""Per-window routing of the swarm: which links are up, and the path each flow takes.

The paper's rule (section 'Network Topology and Routing'): every UAV links to its nearest peer,
UAV or BS, by Euclidean distance; every UAV cluster that reaches no BS gets one bridge link, from
its UAV closest to a BS to that BS; BS switches are interconnected (wired backhaul). A wormhole
adds the victim -> attacker and attacker -> nearest-BS links and forces the victim's BS traffic
through the attacker's switch.

Everything is ordered by node index and ties break towards the lower index, so the result never
depends on set or hash order.
"""

from __future__ import annotations

from collections import deque
from dataclasses import dataclass

import numpy as np

Edge = tuple[int, int]  # (i, j) with i < j, node indices


@dataclass(frozen=True)
class Topology:
    """Active links of one window, as sorted index pairs, and why each exists."""

    edges: tuple[Edge, ...]
    reasons: tuple[str, ...]  # "nearest", "bridge", "backhaul", "detour" per edge
    overrides: tuple[tuple[int, int, int], ...] = ()  # (victim, attacker, bs) wormhole detours

    def adjacency(self, n: int) -> list[list[int]]:
        adj: list[list[int]] = [[] for _ in range(n)]
        for i, j in self.edges:
            adj[i].append(j)
            adj[j].append(i)
        for a in adj:
            a.sort()
        return adj


def _edge(i: int, j: int) -> Edge:
    return (i, j) if i < j else (j, i)


def _distances(pos: np.ndarray) -> np.ndarray:
    diff = pos[:, None, :] - pos[None, :, :]
    return np.sqrt((diff**2).sum(-1))


def _components(n: int, edges: dict[Edge, str]) -> list[list[int]]:
    """Connected components, each sorted, listed by their smallest member."""
    parent = list(range(n))

    def find(x: int) -> int:
        while parent[x] != x:
            parent[x] = parent[parent[x]]
            x = parent[x]
        return x

    for i, j in edges:
        ri, rj = find(i), find(j)
        if ri != rj:
            parent[max(ri, rj)] = min(ri, rj)
    groups: dict[int, list[int]] = {}
    for x in range(n):
        groups.setdefault(find(x), []).append(x)
    return [groups[k] for k in sorted(groups)]


def nearest_neighbour_topology(pos: np.ndarray, is_bs: np.ndarray) -> Topology:
    """The paper's routing: nearest peer per UAV, one bridge per BS-less cluster, BS mesh."""
    pos = np.asarray(pos, dtype=float)
    is_bs = np.asarray(is_bs, dtype=bool)
    n = len(pos)
    if n == 0 or not is_bs.any():
        raise ValueError("routing needs at least one base station")
    dist = _distances(pos)
    np.fill_diagonal(dist, np.inf)
    edges: dict[Edge, str] = {}
    for u in np.flatnonzero(~is_bs):
        edges.setdefault(_edge(int(u), int(np.argmin(dist[u]))), "nearest")
    bs = np.flatnonzero(is_bs)
    for a in range(len(bs)):
        for b in range(a + 1, len(bs)):
            edges.setdefault(_edge(int(bs[a]), int(bs[b])), "backhaul")
    for comp in _components(n, edges):
        if any(is_bs[c] for c in comp):
            continue
        members = np.asarray(comp)
        d_to_bs = dist[np.ix_(members, bs)]
        flat = int(np.argmin(d_to_bs))  # row-major: lowest UAV index, then lowest BS, on ties
        u, b = members[flat // len(bs)], bs[flat % len(bs)]
        edges[_edge(int(u), int(b))] = "bridge"
    order = sorted(edges)
    return Topology(edges=tuple(order), reasons=tuple(edges[e] for e in order))


def with_wormholes(
    topo: Topology, pos: np.ndarray, is_bs: np.ndarray, pairs: list[tuple[int, int]]
) -> Topology:
    """Add wormhole detours: (victim, attacker) pairs, victims attach to the attacker's switch."""
    dist = _distances(np.asarray(pos, dtype=float))
    bs = np.flatnonzero(np.asarray(is_bs, dtype=bool))
    edges = dict(zip(topo.edges, topo.reasons))
    overrides = list(topo.overrides)
    for victim, attacker in pairs:
        if victim == attacker or is_bs[victim] or is_bs[attacker]:
            raise ValueError("wormhole victim and attacker must be two different UAVs")
        b = int(bs[int(np.argmin(dist[attacker, bs]))])
        edges.setdefault(_edge(victim, attacker), "detour")
        edges.setdefault(_edge(attacker, b), "detour")
        overrides.append((victim, attacker, b))
    order = sorted(edges)
    return Topology(tuple(order), tuple(edges[e] for e in order), tuple(overrides))


def shortest_path(adj: list[list[int]], src: int, dst: int, avoid: frozenset[int] = frozenset()) -> list[int]:
    """BFS shortest path, neighbours visited in index order (so ties go to lower indices)."""
    if src == dst:
        return [src]
    prev = {src: src}
    queue = deque([src])
    while queue:
        x = queue.popleft()
        for y in adj[x]:
            if y in prev or y in avoid:
                continue
            prev[y] = x
            if y == dst:
                path = [dst]
                while path[-1] != src:
                    path.append(prev[path[-1]])
                return path[::-1]
            queue.append(y)
    raise ValueError(f"no path from node {src} to node {dst}")


def route(topo: Topology, n: int, src: int, dst: int, is_bs: np.ndarray) -> list[int]:
    """The path a flow src -> dst takes, honouring wormhole detours for a victim's BS traffic."""
    adj = topo.adjacency(n)
    for victim, attacker, _bs in topo.overrides:
        if src == victim and is_bs[dst]:
            return [victim] + shortest_path(adj, attacker, dst, avoid=frozenset({victim}))
        if dst == victim and is_bs[src]:
            return shortest_path(adj, src, attacker, avoid=frozenset({victim})) + [victim]
    return shortest_path(adj, src, dst)


def is_connected_to_bs(topo: Topology, n: int, is_bs: np.ndarray) -> bool:
    comps = _components(n, dict(zip(topo.edges, topo.reasons)))
    return all(any(is_bs[c] for c in comp) for comp in comps)
