"""Per-window routing of the swarm by link quality: which links are up, and the path each flow takes.

The paper's rule (section 'Network Topology and Routing'), made power-aware as the paper intends:
- a link is *usable* when its residual (post-ARQ) loss is below `USABLE_LOSS_MAX`; base-station
  backhaul is wired and always usable;
- every UAV links to its nearest peer (UAV or BS, Euclidean distance) among its usable links;
- every UAV cluster that reaches no BS gets one bridge: the usable link from one of its UAVs to a
  node already connected to a BS that gives the best path to a BS (least ETX, below; then the
  shorter link), bridging clusters one at a time, best first, so a cluster may bridge through one
  bridged before it (with every link usable this is the paper's bridge: the UAV closest to a BS,
  to that BS);
- BS switches are interconnected (wired backhaul);
- a UAV left in a cluster with no usable link to any connected node is *disconnected* for the
  window: it gets no route (no hop over a dead link), and the plan says so.
Paths follow the least expected transmission count (ETX, De Couto et al., MobiCom 2003:
1 / (d_f * d_r) with delivery ratios d = 1 - loss in each direction), then the fewest hops.

Why 0.2: with the fading-averaged link chain (issue 13) residual loss is no longer on/off: over
the 10 dBm benign plans of issue 12 (calibrated profile, every UAV pair, every window) 23 % of
pairs lose < 0.1 of their frames, 9 % lose 0.1-0.2, 16 % 0.2-0.5 and 52 % more. The threshold is
the largest loss at which the benign traffic (a new TCP connection per image, curl's 2 s connect
deadline, SYN retried after 1 s) still works: a connect needs SYN and SYN-ACK through and gets two
tries, so over one hop it fails with probability (1 - (1 - p)^2)^2, 3.6 % at p = 0.1, 13 % at
0.2 and 56 % at 0.5. At 0.1 the same plans leave 10.6 % of UAV-windows disconnected, at 0.2
3.1 % (`benchmarks/routing_quality.py`); no route crosses a hop with loss >= 0.5 either way.

A wormhole adds a detour: the victim's usable link to the attacker, then the attacker's best usable
path to the victim's BS not through the victim (its direct link to a BS allowed). Detour links are
marked so forwarding uses them only for the victim's own traffic (`network.forwarding`).

Everything is ordered by node index and ties break towards the lower index, so the result never
depends on set or hash order.
"""

from __future__ import annotations

import heapq
from dataclasses import dataclass

import numpy as np

Edge = tuple[int, int]  # (i, j) with i < j, node indices

USABLE_LOSS_MAX = 0.2
BACKHAUL_COST = 1.0  # a wired hop: ETX of a lossless link


@dataclass(frozen=True)
class Detour:
    """A wormhole detour: the victim's traffic to and from `bs` takes `path` (victim ... bs)."""

    victim: int
    attacker: int
    bs: int
    path: tuple[int, ...]


@dataclass(frozen=True)
class Topology:
    """Active links of one window, as sorted index pairs, why each exists and what it costs."""

    edges: tuple[Edge, ...]
    reasons: tuple[str, ...]  # "nearest", "bridge", "backhaul", "detour" per edge
    costs: tuple[float, ...] = ()  # ETX per edge; empty: every edge costs 1 (hop count)
    disconnected: tuple[int, ...] = ()  # UAVs with no usable path to any BS
    detours: tuple[Detour, ...] = ()

    def cost(self, k: int) -> float:
        return self.costs[k] if self.costs else 1.0

    def adjacency(self, n: int, with_detours: bool = False) -> list[list[tuple[int, float]]]:
        """Neighbours (index order) and edge costs; detour edges only when asked for."""
        adj: list[list[tuple[int, float]]] = [[] for _ in range(n)]
        for k, (i, j) in enumerate(self.edges):
            if self.reasons[k] == "detour" and not with_detours:
                continue
            adj[i].append((j, self.cost(k)))
            adj[j].append((i, self.cost(k)))
        for a in adj:
            a.sort()
        return adj


def _edge(i: int, j: int) -> Edge:
    return (i, j) if i < j else (j, i)


def _distances(pos: np.ndarray) -> np.ndarray:
    diff = pos[:, None, :] - pos[None, :, :]
    return np.sqrt((diff**2).sum(-1))


def etx(loss: np.ndarray | float) -> np.ndarray:
    """Expected transmissions of a link with this loss in each direction (inf when dead)."""
    p = np.asarray(loss, dtype=float)
    with np.errstate(divide="ignore"):
        return np.where(p < 1.0, 1.0 / np.square(1.0 - np.minimum(p, 1.0)), np.inf)


def _components(n: int, edges) -> list[list[int]]:
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


def _usable(n: int, is_bs: np.ndarray, loss: np.ndarray | None, loss_max: float) -> tuple[np.ndarray, np.ndarray]:
    """Usable-link mask and link costs (ETX; 1 everywhere without a loss matrix)."""
    if loss is None:
        usable, cost = np.ones((n, n), dtype=bool), np.ones((n, n))
    else:
        loss = np.asarray(loss, dtype=float)
        if loss.shape != (n, n):
            raise ValueError(f"loss matrix must be {n}x{n}, got {loss.shape}")
        usable, cost = loss < loss_max, etx(loss)
    both_bs = np.outer(is_bs, is_bs)
    usable = usable | both_bs
    cost = np.where(both_bs, BACKHAUL_COST, cost)
    np.fill_diagonal(usable, False)
    return usable, cost


def _costs_to_bs(n: int, edges: dict[Edge, float], is_bs: np.ndarray) -> np.ndarray:
    """Least path cost from every node to its nearest BS over `edges` (inf: no path)."""
    adj: list[list[tuple[int, float]]] = [[] for _ in range(n)]
    for (i, j), c in edges.items():
        adj[i].append((j, c))
        adj[j].append((i, c))
    best = np.full(n, np.inf)
    heap = [(0.0, int(b)) for b in np.flatnonzero(is_bs)]
    for c, b in heap:
        best[b] = c
    while heap:
        c, x = heapq.heappop(heap)
        if c > best[x]:
            continue
        for y, w in adj[x]:
            if c + w < best[y]:
                best[y] = c + w
                heapq.heappush(heap, (c + w, y))
    return best


def nearest_neighbour_topology(
    pos: np.ndarray, is_bs: np.ndarray, loss: np.ndarray | None = None, loss_max: float = USABLE_LOSS_MAX
) -> Topology:
    """The routing of the module docstring. `loss` (n x n, symmetric) is each pair's residual loss;
    without it every link is usable (the paper's distance-only rule)."""
    pos = np.asarray(pos, dtype=float)
    is_bs = np.asarray(is_bs, dtype=bool)
    n = len(pos)
    if n == 0 or not is_bs.any():
        raise ValueError("routing needs at least one base station")
    usable, cost = _usable(n, is_bs, loss, loss_max)
    dist = _distances(pos)
    edges: dict[Edge, str] = {}
    for u in np.flatnonzero(~is_bs):
        d = np.where(usable[u], dist[u], np.inf)
        if np.isfinite(d).any():
            edges.setdefault(_edge(int(u), int(np.argmin(d))), "nearest")
    bs = np.flatnonzero(is_bs)
    for a in range(len(bs)):
        for b in range(a + 1, len(bs)):
            edges.setdefault(_edge(int(bs[a]), int(bs[b])), "backhaul")
    while True:
        stranded = [c for c in _components(n, edges) if not any(is_bs[x] for x in c)]
        if not stranded:
            break
        to_bs = _costs_to_bs(n, {e: float(cost[e]) for e in edges}, is_bs)
        # Best path to a BS first, then the shorter link (the paper's rule when every link is
        # usable: the UAV closest to a BS bridges to that BS), then the lower indices.
        best: tuple[float, float, int, int] | None = None
        for comp in stranded:
            for u in comp:
                for x in np.flatnonzero(usable[u] & np.isfinite(to_bs)):
                    cand = (float(cost[u, x] + to_bs[x]), float(dist[u, x]), u, int(x))
                    best = cand if best is None or cand < best else best
        if best is None:
            break
        edges[_edge(best[2], best[3])] = "bridge"
    reached = np.isfinite(_costs_to_bs(n, {e: 1.0 for e in edges}, is_bs))
    order = sorted(edges)
    return Topology(
        edges=tuple(order),
        reasons=tuple(edges[e] for e in order),
        costs=tuple(float(cost[e]) for e in order) if loss is not None else (),
        disconnected=tuple(int(u) for u in np.flatnonzero(~is_bs & ~reached)),
    )


def best_path(adj: list[list[tuple[int, float]]], src: int, dst: int,
              avoid: frozenset[int] = frozenset()) -> list[int] | None:
    """Least-cost path (then fewest hops, then lexicographically smallest); None without one."""
    heap: list[tuple[float, int, tuple[int, ...]]] = [(0.0, 0, (src,))]
    done: set[int] = set()
    while heap:
        c, h, path = heapq.heappop(heap)
        x = path[-1]
        if x in done:
            continue
        done.add(x)
        if x == dst:
            return list(path)
        for y, w in adj[x]:
            if y not in done and y not in avoid:
                heapq.heappush(heap, (c + w, h + 1, path + (y,)))
    return None


def route(topo: Topology, n: int, src: int, dst: int) -> list[int] | None:
    """The path a flow src -> dst takes over the window's links (detours excluded); None: none."""
    return best_path(topo.adjacency(n), src, dst)


def with_wormholes(
    topo: Topology, pos: np.ndarray, is_bs: np.ndarray, attacks: list[tuple[int, int, int]],
    loss: np.ndarray | None = None, loss_max: float = USABLE_LOSS_MAX,
) -> Topology:
    """Add the detours of (victim, attacker, bs) wormholes that have one over usable links.

    The detour is the victim's usable link to the attacker, then the attacker's best path to `bs`
    over the window's links or its direct usable links to base stations, never through the victim.
    A wormhole without such a detour this window is left out (its attack moves no traffic).
    """
    is_bs = np.asarray(is_bs, dtype=bool)
    n = len(is_bs)
    usable, cost = _usable(n, is_bs, loss, loss_max)
    edges = {e: (r, topo.cost(k)) for k, (e, r) in enumerate(zip(topo.edges, topo.reasons))}
    detours = list(topo.detours)
    for victim, attacker, bs in attacks:
        if victim == attacker or is_bs[victim] or is_bs[attacker] or not is_bs[bs]:
            raise ValueError("wormhole victim and attacker must be two different UAVs, and bs a base station")
        if not usable[victim, attacker]:
            continue
        adj = topo.adjacency(n)
        for b in np.flatnonzero(is_bs & usable[attacker]):
            if (int(b), cost[attacker, b]) not in adj[attacker]:
                adj[attacker].append((int(b), float(cost[attacker, b])))
                adj[int(b)].append((attacker, float(cost[attacker, b])))
        tail = best_path([sorted(a) for a in adj], attacker, bs, avoid=frozenset({victim}))
        if tail is None:
            continue
        path = (victim, *tail)
        for a, b in zip(path, path[1:]):
            edges.setdefault(_edge(a, b), ("detour", float(cost[a, b])))
        detours.append(Detour(victim, attacker, bs, path))
    order = sorted(edges)
    return Topology(
        edges=tuple(order),
        reasons=tuple(edges[e][0] for e in order),
        costs=tuple(edges[e][1] for e in order) if topo.costs or loss is not None else (),
        disconnected=topo.disconnected,
        detours=tuple(detours),
    )
