"""The L2 "controller": static forwarding for every (switch, destination) pair of a window.

Flooding and learning are off on every switch port (a flooding mesh of bridges is a broadcast
storm), so a frame reaches its destination only through the static FDB computed here. Pure
function of the window; no kernel access, so it is unit-tested without root.

Order of precedence for the next hop towards destination d:
1. shortest paths over the window's active links, wormhole detour links excepted (BFS from d,
   neighbours visited in plan order: deterministic tie-breaking), which gives a loop-free tree
   per destination;
2. the plan's routes (both directions), applied where they do not create a loop.
Every route is a simple path laid onto the tree; the result is checked loop-free per
destination, and a route that would create a loop is rejected (and reported).

Wormhole detours do not touch those trees: a switch forwards by destination MAC only, so laying
victim -> attacker -> bs onto the tree towards bs would drag every frame to bs that crosses the
victim's switch along. Instead each active detour gets two *alias* destinations, "victim>bs"
and "bs>victim", forwarded hop by hop along the detour's path (and back). The fabric rewrites
the destination MAC of the victim's frames to bs (and of bs's frames to the victim) to the
alias at the sender's switch and back at the receiver's switch (`Fabric.detour_ruleset`), so
exactly the victim <-> bs traffic takes the detour, in both directions, and nothing else does.
"""

from __future__ import annotations

from collections import deque
from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field

NextHops = dict[str, dict[str, str]]  # switch (node name) -> destination -> neighbour


@dataclass(frozen=True)
class Detour:
    """A wormhole detour: victim <-> bs traffic takes `hops` (victim, ..., attacker, ..., bs)."""

    victim: str
    attacker: str
    bs: str
    hops: tuple[str, ...] = ()  # empty: the controller finds a simple path through the attacker

    @classmethod
    def of(cls, x: "Detour | Sequence[str]", hops: Sequence[str] = ()) -> "Detour":
        return x if isinstance(x, Detour) else cls(x[0], x[1], x[2], tuple(hops))

    @property
    def key(self) -> str:
        return f"{self.victim}>{self.bs}"

    def alias_hops(self) -> dict[tuple[str, str], tuple[str, str]]:
        """(switch, alias) -> (next switch, alias): 'victim>bs' along the path, 'bs>victim' back.
        The last switch of each direction has no entry: it restores the real MAC first."""
        fwd, back = f"{self.victim}>{self.bs}", f"{self.bs}>{self.victim}"
        out: dict[tuple[str, str], tuple[str, str]] = {}
        for a, b in zip(self.hops, self.hops[1:]):
            out[(a, fwd)] = (b, fwd)
            out[(b, back)] = (a, back)
        return out


@dataclass(frozen=True)
class Forwarding:
    next_hop: NextHops  # only entries for destinations reachable from that switch
    rejected: list[str] = field(default_factory=list)  # overrides that could not be honoured
    detours: tuple[Detour, ...] = ()  # installed wormhole detours, hops filled in

    def detour_path(self, victim: str, bs: str) -> list[str] | None:
        for d in self.detours:
            if (d.victim, d.bs) == (victim, bs):
                return list(d.hops)
        return None

    def path(self, src: str, dst: str) -> list[str] | None:
        """The switch sequence a frame from src to dst follows (None: dropped)."""
        hops = [src]
        while hops[-1] != dst:
            nxt = self.next_hop.get(hops[-1], {}).get(dst)
            if nxt is None or len(hops) > len(self.next_hop) + 1:
                return None
            hops.append(nxt)
        return hops


def adjacency(nodes: Sequence[str], links: Iterable[tuple[str, str]]) -> dict[str, list[str]]:
    order = {n: i for i, n in enumerate(nodes)}
    adj: dict[str, set[str]] = {n: set() for n in nodes}
    for a, b in links:
        if a == b or a not in adj or b not in adj:
            raise ValueError(f"bad link {a}-{b}")
        adj[a].add(b)
        adj[b].add(a)
    return {n: sorted(nb, key=order.__getitem__) for n, nb in adj.items()}


def _bfs_parents(adj: dict[str, list[str]], root: str, banned: frozenset[str] = frozenset()) -> dict[str, str]:
    """parent[x] = neighbour of x one hop closer to root (first found in plan order)."""
    parent = {root: root}
    queue = deque([root])
    while queue:
        u = queue.popleft()
        for v in adj[u]:
            if v not in parent and v not in banned:
                parent[v] = u
                queue.append(v)
    return parent


def shortest_path(adj: dict[str, list[str]], src: str, dst: str,
                  banned: frozenset[str] = frozenset()) -> list[str] | None:
    parent = _bfs_parents(adj, dst, banned - {src, dst})
    if src not in parent:
        return None
    path = [src]
    while path[-1] != dst:
        path.append(parent[path[-1]])
    return path


def _loop_free(nh: dict[str, str], dst: str) -> bool:
    for start in nh:
        seen = set()
        x = start
        while x != dst:
            if x in seen or x not in nh:
                return False
            seen.add(x)
            x = nh[x]
    return True


def _lay(nh: dict[str, str], path: Sequence[str], adj: dict[str, list[str]]) -> bool:
    """Lay `path` (ending at the destination) onto next-hop map `nh` if it stays loop-free."""
    if len(set(path)) != len(path) or any(b not in adj[a] for a, b in zip(path, path[1:])):
        return False
    trial = dict(nh)
    for a, b in zip(path, path[1:]):
        trial[a] = b
    if not _loop_free(trial, path[-1]):
        return False
    nh.update(trial)
    return True


def compute(nodes: Sequence[str], links: Iterable[tuple[str, str]],
            routes: Iterable[Sequence[str]] = (),
            wormholes: Iterable["Detour | Sequence[str]"] = (),
            detour_links: Iterable[tuple[str, str]] = ()) -> Forwarding:
    """Static forwarding for one window.

    nodes: all node names in plan order; links: active undirected links; routes: hop lists
    (ends included) from Window.routes; wormholes: active detours (`Detour`, or (victim,
    attacker, bs) triples whose path the controller finds); detour_links: the links (among
    `links`) that exist for the detours only.
    """
    links = list(links)
    adj = adjacency(nodes, links)
    skip = {frozenset(e) for e in detour_links}
    base = adjacency(nodes, [e for e in links if frozenset(e) not in skip])
    per_dst: dict[str, dict[str, str]] = {}
    for d in nodes:
        parent = _bfs_parents(base, d)
        per_dst[d] = {x: p for x, p in parent.items() if x != d}
    rejected: list[str] = []
    for hops in routes:
        hops = list(hops)
        for p in (hops, hops[::-1]):
            if len(p) >= 2 and not _lay(per_dst[p[-1]], p, base):
                rejected.append(f"route {'>'.join(p)}")
    detours: list[Detour] = []
    for w in wormholes:
        d = Detour.of(w)
        path = list(d.hops) or _via(adj, d.victim, d.attacker, d.bs)
        ok = (path is not None and len(path) >= 2 and path[0] == d.victim and path[-1] == d.bs
              and d.attacker in path and len(set(path)) == len(path)
              and all(b in adj[a] for a, b in zip(path, path[1:])))
        if ok:
            detours.append(Detour(d.victim, d.attacker, d.bs, tuple(path)))
        else:
            rejected.append(f"wormhole {d.victim}>{d.attacker}>{d.bs}")
    next_hop: NextHops = {n: {} for n in nodes}
    for d, nh in per_dst.items():
        for x, y in nh.items():
            next_hop[x][d] = y
    return Forwarding(next_hop, rejected, tuple(detours))


def _via(adj: dict[str, list[str]], src: str, mid: str, dst: str) -> list[str] | None:
    """A simple path src -> mid -> dst (prefers a second leg disjoint from the first)."""
    if mid in (src, dst):
        return shortest_path(adj, src, dst)
    first = shortest_path(adj, src, mid, banned=frozenset({dst}))
    if first is None:
        return None
    second = shortest_path(adj, mid, dst, banned=frozenset(first[:-1]))
    if second is None:
        return None
    return first + second[1:]
