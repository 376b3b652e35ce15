"""Small hand-made plans with attacks for the run/attack tests (3-5 nodes, 2-3 short windows)."""

from __future__ import annotations

from uavcas.attacks import family as attack_family
from uavcas.twin.load import plan_from_data
from uavcas.twin.model import Attack, Link, Node, Plan, Route, Window, WormholeOverride


def nodes(uavs: int, bss: int = 1) -> list[Node]:
    out = [Node(name=f"uav{i}", kind="uav", index=i, ip=f"10.79.1.{i + 1}", mac=f"02:00:00:79:01:{i:02x}")
           for i in range(uavs)]
    out += [Node(name=f"bs{k}", kind="bs", index=uavs + k, ip=f"10.79.0.{k + 1}", mac=f"02:00:00:79:00:{k:02x}")
            for k in range(bss)]
    return out


def link(a: str, b: str, rate_mbps: float = 50.0, delay_ms: float = 0.5, loss: float = 0.0) -> Link:
    return Link(a=a, b=b, kind="air", distance_m=100.0, pathloss_db=80.0, snr_db=25.0, mcs=5,
                rate_mbps=rate_mbps, delay_ms=delay_ms, loss=loss)


def make_plan(ns: list[Node], links: list[Link], attacks: list[Attack], n_windows: int = 2, window_s: float = 4.0,
              routes: list[list[str]] = (), wormholes: list[tuple[str, str, str]] = (), config: str = "test") -> Plan:
    wins = [Window(index=k, t_s=k * window_s, duration_s=window_s, positions={}, links=links,
                   routes=[Route(src=r[0], dst=r[-1], hops=list(r)) for r in routes],
                   wormholes=[WormholeOverride(victim=v, attacker=a, bs=b) for v, a, b in wormholes])
            for k in range(n_windows)]
    # read as a plan.json is: a config that is a scenario gives the plan its typed scenario
    return plan_from_data(dict(config=config, seed=5, window_s=window_s, profile="test",
                               area_m=(1000.0, 1000.0, 30.0, 110.0), nodes=ns, windows=wins, attacks=attacks))


def attack(family: str, attackers: list[str], victim: str, start_s: float, stop_s: float, k: int = 0,
           **params) -> Attack:
    if family in ("dos", "ddos"):
        params.setdefault("interval_us", 1000)
        params.setdefault("nominal_pps", 1e6 / params["interval_us"])
    return Attack(attack_id=f"{family}-{k}", family=family, attackers=attackers, victims=[victim],
                  start_s=start_s, stop_s=stop_s, params=params, spec=attack_family(family).spec_from_params(params))
