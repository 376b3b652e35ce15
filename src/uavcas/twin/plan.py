"""`plan(scenario, seed) -> Plan`: what the twin should do, window by window.

Pure and deterministic: no clock, no environment, no global RNG. Independent seeded streams for
base-station placement, mobility, shadowing and the attack schedule, so changing one (say, the
attack draw) leaves the others as they were.

Per window k (t = k * window_s): mobility gives positions; the channel chain gives every node pair
its rate, delay and loss (evaluated for every pair each window, active or not, so correlated
shadowing evolves with the geometry rather than with the routing); the routing rule
(`topology.routing`) picks the active links among the usable ones, plus the detours of
traffic-detouring attacks while one is scheduled, and marks UAVs that reach no BS disconnected.
The active air links then share the channel's airtime with the links in their carrier-sense
range: a link's rate is its share of the DCF capacity. The run's link chain
(`uavcas.channel.linkchain.LinkChain`, `Channel.chain`) gives the per-link values, the hearing
matrix and the shares; `uavcas channel predict` calls the same chain.

An attack that places a radio emitter (a jammer: `AttackFamily.emitter`, placed from a stream of
its own) adds, while it is on, its interference to the noise floor of the links' receivers; the
window records the emitter and the link directions it changes (`twin.interference`).

The profile (default: the calibrated one shipped with uavcas) is recorded in the plan by name
and by the SHA-256 of its JSON.
"""

from __future__ import annotations

import numpy as np

from uavcas import seeding
from uavcas.attacks import EmitterContext, family
from uavcas.channel import Channel, LinkChain
from uavcas.mobility import Area, make_mission
from uavcas.scenario import Scenario, parse
from uavcas.topology.routing import Topology, nearest_neighbour_topology, route, with_wormholes
from uavcas.traffic.apps import MAVLINK_PAYLOADS

from .interference import window_interference
from .model import (
    DEFAULT_STREAM_HZ,
    MAX_STREAM_HZ,
    Attack,
    Link,
    Node,
    Plan,
    Route,
    Window,
    WormholeOverride,
    mavlink_sysid,
)
from .profile import TwinProfile, load_profile, profile_sha256
from .schedule import schedule_attacks

# Numbered streams of the plan's seed (uavcas.seeding, int keys); never renumber (it would change every plan).
_BS_STREAM, _MOBILITY_STREAM, _CHANNEL_STREAM, _ATTACK_STREAM, _EMITTER_STREAM = 1, 2, 3, 4, 5


def node_ip(kind: str, k: int) -> str:
    """UAV k -> 10.77.1.(k+1), BS k -> 10.77.0.(k+1): one private /16 per emulation."""
    return f"10.77.{1 if kind == 'uav' else 0}.{k + 1}"


def node_mac(index: int) -> str:
    # Locally administered unicast (02:...), "ua" in the second octet, the node index after.
    return f"02:75:61:00:{index >> 8:02x}:{index & 0xFF:02x}"


def _nodes(scenario: Scenario) -> list[Node]:
    if scenario.payload in MAVLINK_PAYLOADS and scenario.n_uav + scenario.n_bs > 255:
        raise ValueError(f"{scenario.n_uav} UAVs + {scenario.n_bs} BSs exceed the 255 MAVLink system ids "
                         f"a {scenario.payload!r} payload needs")
    nodes = []
    for k in range(scenario.n_uav):
        nodes.append(Node(name=f"uav{k}", kind="uav", index=k, ip=node_ip("uav", k), mac=node_mac(k),
                          sysid=mavlink_sysid("uav", k)))
    for k in range(scenario.n_bs):
        i = scenario.n_uav + k
        nodes.append(Node(name=f"bs{k}", kind="bs", index=i, ip=node_ip("bs", k), mac=node_mac(i),
                          sysid=mavlink_sysid("bs", k)))
    return nodes


def _rng(seed: int, stream: int) -> np.random.Generator:
    return seeding.generator(seed, stream)


def _child_seed(seed: int, stream: int) -> int:
    return seeding.child_seed(seed, stream)


def _bs_positions(n_bs: int, area: Area, mast_m: float, rng: np.random.Generator) -> np.ndarray:
    margin = 0.1 * min(area.x_max_m, area.y_max_m)
    xy = rng.uniform([margin, margin], [area.x_max_m - margin, area.y_max_m - margin], (n_bs, 2))
    return np.c_[xy, np.full(n_bs, mast_m)]


def _round(x: float, nd: int) -> float:
    return float(round(float(x), nd))


def plan(
    scenario: Scenario | str,
    seed: int = 0,
    windows: int = 12,
    window_s: float = 5.0,
    profile: TwinProfile | str | None = None,
    rounds: int = 1,
    stream_hz: int = DEFAULT_STREAM_HZ,
) -> Plan:
    if isinstance(scenario, str):
        scenario = parse(scenario)
    if windows < 1:
        raise ValueError(f"windows must be >= 1, got {windows}")
    if not window_s > 0:
        raise ValueError(f"window_s must be > 0, got {window_s}")
    if isinstance(stream_hz, bool) or not isinstance(stream_hz, int) or not 1 <= stream_hz <= MAX_STREAM_HZ:
        raise ValueError(f"stream_hz must be an integer in 1..{MAX_STREAM_HZ}, got {stream_hz!r}")
    prof = profile if isinstance(profile, TwinProfile) else load_profile(profile)
    area = prof.area
    nodes = _nodes(scenario)
    n_uav, n = scenario.n_uav, len(nodes)
    names = [nd.name for nd in nodes]
    is_bs = np.array([nd.kind == "bs" for nd in nodes])

    bs_pos = _bs_positions(scenario.n_bs, area, prof.bs_mast_m, _rng(seed, _BS_STREAM))
    mission = make_mission(
        scenario.mission, n_uav, seed=_child_seed(seed, _MOBILITY_STREAM), area=area,
        params=prof.mobility_params(scenario.mission),
    )
    times = np.arange(windows) * window_s
    uav_tracks = np.asarray(mission.positions(times), dtype=float)  # (windows, n_uav, 3)
    channel = Channel(
        pathloss=scenario.pathloss,
        profile=prof.pathloss,
        seed=_child_seed(seed, _CHANNEL_STREAM),
        tx_power_dbm=float(scenario.tx_dbm),
        noise_dbm=scenario.noise_dbm,
        modulation=scenario.fixed_mcs if scenario.fixed_mcs is not None else "adaptive",
        n_nodes=n,
        **prof.channel_kwargs(),
    )
    iu, ju = np.triu_indices(n, k=1)
    all_pairs = np.c_[iu, ju]
    pair_index = {(int(a), int(b)): k for k, (a, b) in enumerate(all_pairs)}
    positions = [np.vstack([uav_tracks[w], bs_pos]) for w in range(windows)]
    # Every pair, every window, in window order: shadowing evolves with the geometry, and routing
    # needs every pair's loss to pick usable links.
    arrs = [channel.evaluate(pos, all_pairs, is_bs) for pos in positions]
    losses = [_loss_matrix(n, all_pairs, arr.loss) for arr in arrs]
    bs_of = [n_uav + u % scenario.n_bs for u in range(n_uav)]

    # The routing without attacks, per window (attacks only add detours to it).
    bases = [nearest_neighbour_topology(positions[w], is_bs, losses[w]) for w in range(windows)]
    def routes_at(t_s: float) -> dict[str, list[str]]:
        """The routes of the window holding t_s: they pick the blackhole relay and an off-path
        wormhole attacker of a round starting then."""
        w = min(int(t_s // window_s), windows - 1)
        return {names[u]: [names[h] for h in route(bases[w], n, u, bs_of[u]) or []] for u in range(n_uav)}

    def detour_windows(victim: str, attacker: str, start_s: float, stop_s: float) -> int:
        """Windows of [start_s, stop_s) in which a wormhole detour victim -> attacker -> BS exists."""
        v, a = names.index(victim), names.index(attacker)
        return sum(bool(with_wormholes(bases[w], positions[w], is_bs, [(v, a, bs_of[v])], losses[w]).detours)
                   for w in range(windows) if w * window_s < stop_s and (w + 1) * window_s > start_s)

    attacks = schedule_attacks(scenario, names[:n_uav], windows * window_s, _rng(seed, _ATTACK_STREAM), routes_at,
                               detour_windows, rounds=rounds)

    # Emitters the attacks place (jammers), drawn from their own stream: other draws stay as they were.
    ectx = EmitterContext(names, float(window_s), np.stack(positions),
                          (area.x_max_m, area.y_max_m, area.z_min_m, area.z_max_m), _rng(seed, _EMITTER_STREAM))
    emitters = [(a, em) for a in attacks if (em := family(a.family).emitter(a, ectx)) is not None]

    out_windows = []
    for w in range(windows):
        t0, t1 = w * window_s, (w + 1) * window_s
        pos, base = positions[w], bases[w]
        detours = [a for a in attacks if family(a.family).detours_traffic and a.start_s < t1 and a.stop_s > t0]
        triples = [(names.index(v), names.index(a.attackers[0]), bs_of[names.index(v)])
                   for a in detours for v in a.victims]
        topo = with_wormholes(base, pos, is_bs, triples, losses[w]) if triples else base
        hears = channel.chain.hears(n, arrs[w].pairs, arrs[w].pathloss_db)
        shared = _shared_rates(topo, arrs[w], pair_index, hears, channel.chain)
        links = [_link(names, topo, e, arrs[w], pair_index[e], prof, shared.get(e)) for e in topo.edges]
        interferers, overrides = window_interference(channel, emitters, w, t0, t1, names, pos, is_bs, links, arrs[w],
                                                     pair_index, hears, prof) if emitters else ([], [])
        out_windows.append(
            Window(
                index=w,
                t_s=_round(t0, 6),
                duration_s=float(window_s),
                positions={names[i]: tuple(_round(c, 3) for c in pos[i]) for i in range(n)},
                links=links,
                routes=_routes(names, base, bs_of, attacks, t0, t1),
                wormholes=[
                    WormholeOverride(victim=names[d.victim], attacker=names[d.attacker], bs=names[d.bs],
                                     hops=[names[h] for h in d.path])
                    for d in topo.detours
                ],
                interferers=interferers,
                link_overrides=overrides,
            )
        )
    return Plan(
        config=scenario.to_string(),
        scenario=scenario,
        seed=seed,
        window_s=float(window_s),
        rounds=rounds,
        profile=prof.name,
        profile_sha256=profile_sha256(prof),
        area_m=(area.x_max_m, area.y_max_m, area.z_min_m, area.z_max_m),
        mavlink_stream_hz=stream_hz,
        nodes=nodes,
        windows=out_windows,
        attacks=attacks,
    )


def _loss(x: float) -> float:
    return min(1.0, max(0.0, _round(x, 8)))


def _loss_matrix(n: int, pairs: np.ndarray, loss: np.ndarray) -> np.ndarray:
    """Symmetric n x n residual loss, rounded as the plan's links carry it."""
    m = np.zeros((n, n))
    vals = np.array([_loss(x) for x in loss])
    m[pairs[:, 0], pairs[:, 1]] = vals
    m[pairs[:, 1], pairs[:, 0]] = vals
    return m


def _shared_rates(topo: Topology, arr, pair_index, hears: np.ndarray, chain: LinkChain) -> dict:
    """Air link -> its share of the DCF airtime among the active air links it contends with
    (`LinkChain.shared_rate_mbps`; empty with the PHY rate model, whose links keep their rates)."""
    air = [e for e, why in zip(topo.edges, topo.reasons) if why != "backhaul"]
    if not air:
        return {}
    idx = np.array([pair_index[e] for e in air])
    rates = chain.shared_rate_mbps(arr.pairs[idx], arr.mac_time_us[idx], hears)
    return {} if rates is None else dict(zip(air, rates))


def _link(names, topo: Topology, edge, arr, k: int, prof: TwinProfile, shared_rate: float | None) -> Link:
    i, j = edge
    reason = topo.reasons[topo.edges.index(edge)]
    if reason == "backhaul":
        return Link(
            a=names[i], b=names[j], kind="backhaul", distance_m=_round(arr.distance_m[k], 3),
            pathloss_db=None, snr_db=None, mcs=None, rate_mbps=prof.backhaul_rate_mbps,
            delay_ms=prof.backhaul_delay_ms, loss=0.0,
        )
    los = None if arr.los is None else bool(arr.los[k])
    return Link(
        a=names[i],
        b=names[j],
        kind="air",
        distance_m=_round(arr.distance_m[k], 3),
        pathloss_db=_round(arr.pathloss_db[k], 3),
        snr_db=_round(arr.snr_db[k], 3),
        mcs=int(arr.mcs[k]),
        rate_mbps=_round(arr.rate_mbps[k] if shared_rate is None else shared_rate, 4),
        delay_ms=_round(arr.delay_ms[k], 4),
        loss=_loss(arr.loss[k]),
        los=los,
        detour=reason == "detour",
    )


def _routes(names, topo: Topology, bs_of: list[int], attacks: list[Attack], t0, t1) -> list[Route]:
    """Benign routes (UAV i <-> BS i mod n_bs) and the attack paths of families that route them."""
    n = len(names)
    wanted: list[tuple[int, int]] = [(u, b) for u, b in enumerate(bs_of)]
    for a in attacks:
        if a.start_s < t1 and a.stop_s > t0 and family(a.family).routes_attack_traffic:
            wanted += [(names.index(x), names.index(v)) for x in a.attackers for v in a.victims]
    seen, out = set(), []
    for s, d in wanted:
        if (s, d) not in seen:
            seen.add((s, d))
            hops = route(topo, n, s, d)
            out.append(Route(src=names[s], dst=names[d], hops=[names[h] for h in hops or []],
                             disconnected=hops is None))
    return out
