"""Hand-made Plans for the emulation tests and benchmarks: exact links and routes, no planner draws."""

from __future__ import annotations

import random

from uavcas.twin import model

Plan, Node, Link, Window, Route, WormholeOverride = (model.Plan, model.Node, model.Link, model.Window,
                                                      model.Route, model.WormholeOverride)


def nodes(n_uav: int, n_bs: int = 0) -> list:
    out = []
    names = [f"uav{i}" for i in range(n_uav)] + [f"bs{i}" for i in range(n_bs)]
    for i, name in enumerate(names):
        out.append(Node(name=name, kind="bs" if name.startswith("bs") else "uav", index=i,
                        ip=f"10.77.{i // 250}.{i % 250 + 1}", mac=f"02:00:00:00:{i // 256:02x}:{i % 256:02x}"))
    return out


def link(a: str, b: str, rate_mbps: float = 100.0, delay_ms: float = 0.0, loss: float = 0.0):
    return Link(a=a, b=b, kind="air", distance_m=100.0, pathloss_db=80.0, snr_db=20.0, mcs=3,
                rate_mbps=rate_mbps, delay_ms=delay_ms, loss=loss)


def window(index: int, links: list, routes: list[list[str]] = (), wormholes: list = ()):
    return Window(index=index, t_s=5.0 * index, duration_s=5.0, positions={}, links=links,
                  routes=[Route(src=r[0], dst=r[-1], hops=list(r)) for r in routes],
                  wormholes=[WormholeOverride(victim=v, attacker=a, bs=b) for v, a, b in wormholes])


def plan(node_list: list, windows: list) -> "Plan":
    return Plan(config="test", seed=0, window_s=5.0, profile="test", area_m=(1000.0, 1000.0, 30.0, 110.0),
                nodes=node_list, windows=windows, attacks=[])


def random_plan(n_uav: int, n_bs: int, n_windows: int, seed: int = 1, p_up: float = 0.6) -> "Plan":
    """Full-mesh candidates, each link up with probability p_up per window, random parameters."""
    rng = random.Random(seed)
    ns = nodes(n_uav, n_bs)
    names = [n.name for n in ns]
    wins = []
    for w in range(n_windows):
        links = [link(a, b, rng.choice([6, 12, 24, 54]), rng.uniform(0.5, 5), rng.choice([0, 0.01, 0.05]))
                 for i, a in enumerate(names) for b in names[i + 1:] if rng.random() < p_up]
        wins.append(window(w, links))
    return plan(ns, wins)


def nn_plan(n_uav: int, n_bs: int, n_windows: int, seed: int = 1) -> "Plan":
    """Sparse, plan-like windows: each node links to 1-2 random earlier nodes (a connected tree+)."""
    rng = random.Random(seed)
    ns = nodes(n_uav, n_bs)
    names = [n.name for n in ns]
    wins = []
    for w in range(n_windows):
        order = names[:]
        rng.shuffle(order)
        pairs = set()
        for k in range(1, len(order)):
            for peer in rng.sample(order[:k], min(k, rng.choice([1, 1, 2]))):
                pairs.add(tuple(sorted((order[k], peer), key=names.index)))
        links = [link(a, b, rng.choice([6, 12, 24, 54]), rng.uniform(0.5, 5), rng.choice([0, 0.01]))
                 for a, b in sorted(pairs)]
        wins.append(window(w, links))
    return plan(ns, wins)
