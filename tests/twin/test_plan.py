import json
import subprocess
import sys

import numpy as np
import pytest

from uavcas.scenario import PRESETS, parse
from uavcas.topology.routing import USABLE_LOSS_MAX, Topology
from uavcas.twin import Plan
from uavcas.twin.load import read_plan
from uavcas.twin.plan import plan

MISSIONS = ("spiral", "grid", "hover_transit", "random")


def _connected(p: Plan) -> bool:
    """Every UAV not marked disconnected reaches a BS over the window's (non-detour) links, every
    marked one does not, and no route crosses an unusable link."""
    idx = {nd.name: nd.index for nd in p.nodes}
    is_bs = np.array([nd.kind == "bs" for nd in p.nodes])
    for w in p.windows:
        edges = tuple(sorted(tuple(sorted((idx[lk.a], idx[lk.b]))) for lk in w.links if not lk.detour))
        loss = {(lk.a, lk.b): lk.loss for lk in w.links} | {(lk.b, lk.a): lk.loss for lk in w.links}
        for r in w.routes:
            if any(loss[h] >= USABLE_LOSS_MAX for h in zip(r.hops, r.hops[1:])):
                return False
        off = set(p.disconnected_uavs(w))
        sub = Topology(edges, ("x",) * len(edges))
        for u in (nd for nd in p.nodes if nd.kind == "uav"):
            if (u.name in off) == _reaches_bs(sub, idx[u.name], is_bs):
                return False
    return True


def _reaches_bs(topo: Topology, u: int, is_bs: np.ndarray) -> bool:
    seen, todo = {u}, [u]
    while todo:
        x = todo.pop()
        if is_bs[x]:
            return True
        for i, j in topo.edges:
            for a, b in ((i, j), (j, i)):
                if a == x and b not in seen:
                    seen.add(b)
                    todo.append(b)
    return False


@pytest.mark.parametrize("mission", MISSIONS)
@pytest.mark.parametrize("pathloss", ("logdist", "3gpp"))
def test_every_window_is_connected_and_routes_are_valid(mission, pathloss):
    p = plan(f"dos=1000-15-2-image-{pathloss}-adaptive-{mission}-10-95", seed=3)
    assert len(p.windows) == 12 and _connected(p)
    for w in p.windows:
        links = {(lk.a, lk.b) for lk in w.links} | {(lk.b, lk.a) for lk in w.links}
        assert {r.src for r in w.routes} >= {f"uav{k}" for k in range(15)}
        for r in w.routes:
            assert all(h in links for h in zip(r.hops, r.hops[1:])), r
            assert r.disconnected == (r.hops == [])
        for lk in w.links:
            assert 0.0 <= lk.loss <= 1.0 and lk.rate_mbps > 0 and lk.delay_ms > 0


def test_disconnected_uavs_are_marked_and_counted():
    # 3 dBm over the 3GPP model: a sparse swarm, some UAVs out of reach of every BS
    p = plan("benign-10-2-image-3gpp-adaptive-random-0-95", seed=1)
    marked = sum(len(p.disconnected_uavs(w)) for w in p.windows)
    assert marked > 0 and _connected(p)
    assert p.disconnected_fraction == marked / (10 * len(p.windows))
    assert all(r.hops == [] for w in p.windows for r in w.routes if r.disconnected)


def test_same_seed_same_bytes_other_seed_other_plan():
    cfg = "blackhole+dos=1000-10-2-image-3gpp-adaptive-random-30-95"
    a, b, c = plan(cfg, seed=5).to_json(), plan(cfg, seed=5).to_json(), plan(cfg, seed=6).to_json()
    assert a == b != c
    assert read_plan(a).to_json() == a


def test_plan_json_has_the_documented_fields():
    d = json.loads(plan("ddos=1000-8-2-image-logdist-adaptive-grid-30-95", seed=1).to_json())
    assert {"config", "seed", "nodes", "windows", "attacks"} <= set(d)
    assert {"name", "kind", "ip"} <= set(d["nodes"][0])
    w = d["windows"][0]
    assert {"t_s", "positions", "links"} <= set(w)
    assert {"a", "b", "distance_m", "pathloss_db", "snr_db", "mcs", "rate_mbps", "delay_ms",
            "loss"} <= set(w["links"][0])
    (atk,) = d["attacks"]
    assert {"family", "attackers", "victims", "start_s", "stop_s", "params"} <= set(atk)
    assert atk["family"] == "ddos" and len(atk["attackers"]) >= 2


@pytest.mark.slow  # 10 s on 2 cores
def test_attack_schedule_follows_the_paper():
    starts = set()
    for seed in range(30):
        p = plan("blackhole+ddos=1000-10-2-image-logdist-adaptive-random-30-95", seed=seed, windows=12)
        bh, dd = sorted(p.attacks, key=lambda a: a.family)
        assert bh.victims == dd.victims and (bh.start_s, bh.stop_s) == (dd.start_s, dd.stop_s)
        assert 10.0 <= dd.stop_s - dd.start_s <= 20.0 and 0 <= dd.start_s and dd.stop_s <= 60.0
        assert len(dd.attackers) >= 2 and not set(dd.attackers) & set(dd.victims)
        assert not set(bh.attackers) & set(dd.attackers)
        assert all(x.startswith("uav") for x in dd.attackers + dd.victims + bh.attackers)
        starts.add(dd.start_s)
    assert len(starts) == 30 and min(starts) > 0.0


def test_wormhole_windows_detour_the_victim_through_the_attacker():
    p = plan("wormhole-10-2-image-logdist-adaptive-spiral-30-95", seed=2)
    (atk,) = p.attacks
    (victim,), (attacker,) = atk.victims, atk.attackers
    hit = [w for w in p.windows if w.t_s < atk.stop_s and w.t_s + w.duration_s > atk.start_s]
    assert hit and any(w.wormholes for w in hit)
    for w in hit:
        links = {(lk.a, lk.b): lk for lk in w.links} | {(lk.b, lk.a): lk for lk in w.links}
        for o in w.wormholes:
            assert (o.victim, o.attacker) == (victim, attacker)
            assert o.hops[:2] == [victim, attacker] and o.hops[-1] == o.bs and victim not in o.hops[1:]
            assert all(links[h].loss < USABLE_LOSS_MAX for h in zip(o.hops, o.hops[1:]))
        (r,) = [r for w2 in [w] for r in w2.routes if r.src == victim]
        assert attacker not in r.hops  # routes stay the undisturbed paths; the detour is the override's
    for w in p.windows:
        if w not in hit:
            assert not w.wormholes and not any(lk.detour for lk in w.links)


@pytest.mark.slow  # 14 s on 2 cores
def test_physics_varies_with_distance_and_tx_power():
    # Across the campaign geometry, MCS, rate and loss depend on the link and on TX power.
    rates, mcs = {}, set()
    for tx in (10, 30):
        vals = []
        for mission in MISSIONS:
            for pl in ("logdist", "3gpp"):
                p = plan(f"benign-20-2-image-{pl}-adaptive-{mission}-{tx}-95", seed=11)
                air = [lk for w in p.windows for lk in w.links if lk.kind == "air"]
                vals += [lk.rate_mbps for lk in air]
                mcs |= {lk.mcs for lk in air}
                d = np.array([lk.distance_m for lk in air])
                snr = np.array([lk.snr_db for lk in air])
                assert np.corrcoef(d, snr)[0, 1] < -0.3  # farther -> weaker
        rates[tx] = np.mean(vals)
    assert len(mcs) >= 4
    assert rates[30] > rates[10]


def test_quick_preset_plans():
    for cfg in PRESETS["quick"].configs:
        p = plan(cfg, seed=1, windows=3)
        assert p.config == cfg and len(p.windows) == 3 and _connected(p)
        assert set(a.family for a in p.attacks) == set(parse(cfg).families)


def _cli(*args):
    return subprocess.run([sys.executable, "-m", "uavcas.cli", *args], capture_output=True, text=True)


@pytest.mark.slow  # 11 s on 2 cores
def test_cli_plan_writes_json_and_figures(tmp_path):
    out, figs = tmp_path / "plan.json", tmp_path / "figs"
    r = _cli("plan", "dos=1000-6-2-image-logdist-adaptive-random-30-95", "--seed", "1", "--windows", "3",
             "--out", str(out), "--figure", str(figs))
    assert r.returncode == 0, r.stderr
    assert "MCS" in r.stdout and "dos-0" in r.stdout
    assert read_plan(out.read_text()).windows[2].index == 2
    assert sorted(p.name for p in figs.glob("*.png")) == [f"topology_w0{k}.png" for k in range(3)]
    again = tmp_path / "again.json"
    assert _cli("plan", "dos=1000-6-2-image-logdist-adaptive-random-30-95", "--seed", "1", "--windows", "3",
                "--out", str(again)).returncode == 0
    assert again.read_bytes() == out.read_bytes()


@pytest.mark.slow  # 4 s on 2 cores
def test_cli_plan_refuses_bad_config(tmp_path):
    r = _cli("plan", "dos=1000-6-2-image-nowhere-adaptive-random-30-95", "--out", str(tmp_path / "p.json"))
    assert r.returncode == 2 and "field 'pathloss'" in r.stderr and not (tmp_path / "p.json").exists()


@pytest.mark.slow  # 4 s on 2 cores
def test_wormhole_attacker_is_off_the_victims_initial_route():
    detoured = 0
    for seed in range(20):
        p = plan("wormhole-8-2-image-logdist-adaptive-random-30-95", seed=seed)
        (atk,) = p.attacks
        (r,) = [r for r in p.windows[0].routes if r.src == atk.victims[0]]
        assert atk.attackers[0] not in r.hops  # the detour adds a hop
        detoured += any(w.wormholes for w in p.windows)
    assert detoured >= 15  # the attacker is drawn among UAVs that have a detour at t = 0


def test_plans_record_the_calibrated_profile_by_default_and_paper_on_request():
    from uavcas.twin.profile import PAPER_PROFILE, load_profile, profile_sha256

    cfg = "benign-5-2-image-logdist-adaptive-grid-10-95"
    default, paper = plan(cfg, seed=2), plan(cfg, seed=2, profile="paper")
    cal = load_profile(None)
    assert default.profile == "calibrated" and default.profile_sha256 == profile_sha256(cal)
    assert paper.profile == "paper" and paper.profile_sha256 == profile_sha256(PAPER_PROFILE)
    assert cal.provenance is not None and cal.provenance.data_files  # shipped with its provenance
    # seed + config + profile -> the same plan, bit for bit.
    assert plan(cfg, seed=2).to_json() == default.to_json() and default.to_json() != paper.to_json()
    # BS masts: the AERPAW LW1 tower (10 m) in the calibrated profile, 25 m in the paper's.
    bs = lambda p: {p.windows[0].positions[n.name][2] for n in p.nodes if n.kind == "bs"}  # noqa: E731
    assert bs(default) == {cal.bs_mast_m} and 9.0 < cal.bs_mast_m < 12.5 and bs(paper) == {25.0}


def test_air_links_share_airtime_and_count_the_mac_time_once():
    from scipy.constants import c

    def rates(n):
        p = plan(f"benign-{n}-2-image-logdist-adaptive-random-30-95", seed=1, windows=4)
        air = [lk for w in p.windows for lk in w.links if lk.kind == "air"]
        for lk in air:  # the MAC time is in the rate only: delay = propagation + processing
            assert lk.delay_ms == pytest.approx(lk.distance_m / c * 1e3 + 0.1, abs=1e-4)
        return np.mean([lk.rate_mbps for lk in air])

    # At 30 dBm everyone hears everyone over 1 km: 20 UAVs' links share one channel, 5 UAVs' fewer.
    assert rates(20) < 0.8 * rates(5)


def test_loss_rises_smoothly_at_10_dbm():
    # Fading-averaged loss: the links between "clean" and "dead" outnumber half the dead ones
    # (issue #13; with the on/off loss of an unfaded chain the middle band was nearly empty).
    mid = dead = 0
    for mission in MISSIONS:
        for pl in ("logdist", "3gpp"):
            p = plan(f"benign-10-2-image-{pl}-adaptive-{mission}-10-95", seed=0, windows=4)
            loss = np.array([lk.loss for w in p.windows for lk in w.links if lk.kind == "air"])
            mid += int(np.count_nonzero((loss > 0.01) & (loss < 0.99)))
            dead += int(np.count_nonzero(loss >= 0.99))
    assert mid >= 0.5 * dead and mid > 0
