"""Wormhole: an off-path attacker, and the detour only while the attack is active."""

from __future__ import annotations

import numpy as np

from uavcas.attacks import ScheduleDraw, family
from uavcas.attacks.wormhole import WormholeSpec
from uavcas.twin.plan import plan


def test_attacker_is_off_the_victims_route_where_possible():
    names = [f"uav{i}" for i in range(5)]
    d = ScheduleDraw(names, "uav0", ["uav3", "uav1", "uav2", "uav4"], {"uav0": ["uav0", "uav3", "uav1", "bs0"]},
                     np.random.default_rng(0))
    assert family("wormhole").attackers(WormholeSpec(), d) == ["uav2"]
    assert "uav2" in d.used
    d2 = ScheduleDraw(names[:2], "uav0", ["uav1"], {"uav0": ["uav0", "uav1", "bs0"]}, np.random.default_rng(0))
    assert family("wormhole").attackers(WormholeSpec(), d2) == ["uav1"]  # nobody off the route: take one


def test_attacker_has_a_detour_in_most_windows_of_the_attack():
    names = [f"uav{i}" for i in range(5)]
    counts = {"uav1": 1, "uav2": 2, "uav4": 2}
    d = ScheduleDraw(names, "uav0", ["uav3", "uav1", "uav4", "uav2"], {"uav0": ["uav0", "uav3", "bs0"]},
                     np.random.default_rng(0), detours=lambda v, a: counts.get(a, 0))
    assert family("wormhole").attackers(WormholeSpec(), d) == ["uav4"]  # 2 windows; first of the ties
    nobody = ScheduleDraw(names, "uav0", ["uav3", "uav1"], {"uav0": ["uav0", "uav3", "bs0"]},
                          np.random.default_rng(0), detours=lambda v, a: 0)
    assert family("wormhole").attackers(WormholeSpec(), nobody) == ["uav1"]  # off the route anyway


def test_planner_detours_the_victim_through_the_attacker_while_scheduled():
    p = plan("wormhole-6-1-image-logdist-adaptive-grid-30-95", seed=4, windows=4, window_s=5.0)
    (a,) = p.attacks
    assert family(a.family).detours_traffic
    for w in p.windows:
        active = a.start_s < w.t_s + w.duration_s and a.stop_s > w.t_s
        overrides = [(o.victim, o.attacker, o.hops[:2]) for o in w.wormholes]
        assert overrides == ([(a.victims[0], a.attackers[0], [a.victims[0], a.attackers[0]])] if active else [])
        assert any(lk.detour for lk in w.links) == active


def test_udp_datagrams_detoured_through_the_attacker_are_wormhole():
    """The rule is about IP packets, not TCP: a MAVLink datagram of the victim detoured through the
    attacker's switch in a planned window, and one after the detour, on the direct link."""
    from helpers.hand_truth import pkt, rows_of, table, window
    from helpers.synth_run import T0, make_plan
    from uavcas.flows.follow import Timeline, follow
    from uavcas.labels.attacklog import AttackLog
    from uavcas.labels.effects import TruthContext, packet_truth

    wplan = make_plan(wormhole=True)
    detoured = pkt(1.0, "uav0", "bs0", 14555, 14550, proto=17, ip_id=0, payload=40, at=["uav0", "uav2", "bs0"])
    direct = pkt(6.0, "uav0", "bs0", 14555, 14550, proto=17, ip_id=0, payload=40)
    t = table([detoured, direct])
    log = AttackLog(windows=(window("wormhole", "uav2", "uav0", 0.5, 3.0),))
    ctx = TruthContext(t, log, follow(t, Timeline.from_plan(wplan, T0)), wplan, T0)
    truth = packet_truth(ctx)
    assert set(truth.effect_names(rows_of(ctx, detoured))) == {"wormhole"} and rows_of(ctx, detoured).sum() == 3
    assert set(truth.effect_names(rows_of(ctx, direct))) == {"benign"}
