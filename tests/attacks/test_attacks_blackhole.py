"""Blackhole: the relay credited with the drop, the nft table on the victim's switch, drops as packet effects."""

from __future__ import annotations

import dataclasses

import numpy as np

from helpers.synth_run import BLACKHOLE_WINDOW, IPS, T0
from uavcas.attacks import ScheduleDraw, family
from uavcas.attacks.blackhole import BlackholeSpec, ruleset, switch_ports, table_name

NAMES = [f"uav{i}" for i in range(5)]


def _draw(routes_start, used=()):
    d = ScheduleDraw(NAMES, "uav0", ["uav3", "uav1", "uav2", "uav4"], routes_start, np.random.default_rng(0))
    d.used.update(used)
    return d


def test_attacker_is_the_victims_first_relay_when_a_uav():
    bh = family("blackhole")
    assert bh.attackers(BlackholeSpec(), _draw({"uav0": ["uav0", "uav2", "bs0"]})) == ["uav2"]
    assert bh.attackers(BlackholeSpec(), _draw({"uav0": ["uav0", "bs0"]})) == ["uav3"]  # BS first: seeded pick
    assert bh.attackers(BlackholeSpec(), _draw({"uav0": ["uav0", "uav2", "bs0"]}, used={"uav2"})) == ["uav3"]


def test_ruleset_drops_ipv4_both_ways_and_never_arp():
    rs = ruleset(table_name("blackhole-0"), ["h2", "l2-*"], "10.9.0.3")
    assert rs.startswith("table bridge uavcas_bh_blackhole_0 ")
    assert 'iifname { "h2", "l2-*" }' in rs
    assert "ip saddr 10.9.0.3 counter drop" in rs and "ip daddr 10.9.0.3 counter drop" in rs
    assert "arp" not in rs and "priority -20" in rs
    assert switch_ports(1) == ["h1", "l1-*"]


def test_effect_is_a_drop_at_the_victims_switch_inside_the_window(truth_ctx):
    (w,) = truth_ctx.log.of_family("blackhole")
    hit = family("blackhole").effects(truth_ctx, [w])
    p = truth_ctx.packets.to_pandas()[hit]
    # the three SYNs of the fetch at 42, each seen at s-bs0 and (last) at s-uav3
    assert len(p) == 6 and (p.dst_ip == IPS["uav3"]).all() and set(p.point) == {"s-bs0", "s-uav3"}
    assert ((p.ts_s >= T0 + BLACKHOLE_WINDOW[0]) & (p.ts_s < T0 + BLACKHOLE_WINDOW[1])).all()
    empty = dataclasses.replace(w, start_unix=T0 + 1000, stop_unix=T0 + 1001)
    assert not family("blackhole").effects(truth_ctx, [empty]).any()
    # A window over the answered session at 32: packets *to* the victim end at its switch either
    # way (only the window tells a drop), but the victim's answers were seen at the next switch:
    # they were not dropped, whatever the window says.
    answered = dataclasses.replace(w, start_unix=T0 + 32.0, stop_unix=T0 + 33.0)
    q = truth_ctx.packets.to_pandas()[family("blackhole").effects(truth_ctx, [answered])]
    assert len(q) and (q.dst_ip == IPS["uav3"]).all()


def test_udp_datagrams_of_the_victim_are_dropped_like_tcp():
    """The rule is about IP packets, not TCP: MAVLink datagrams to and from the blackholed UAV."""
    from helpers.hand_truth import context, pkt, rows_of, window
    from uavcas.labels.effects import packet_truth

    cmd = pkt(42.0, "bs0", "uav3", 14550, 14555, proto=17, ip_id=0, payload=41)  # reaches s-uav3, no further
    telemetry = pkt(42.5, "uav3", "bs0", 14555, 14550, proto=17, ip_id=0, payload=40, at=["uav3"])
    before = pkt(35.0, "uav3", "bs0", 14555, 14550, proto=17, ip_id=0, payload=40)
    other = pkt(42.2, "bs0", "uav0", 14550, 14555, proto=17, ip_id=0, payload=41)
    ctx = context([cmd, telemetry, before, other], [window("blackhole", "uav2", "uav3", 40.0, 50.0)])
    truth = packet_truth(ctx)
    for p in (cmd, telemetry):
        assert set(truth.effect_names(rows_of(ctx, p))) == {"blackhole"}
    for p in (before, other):
        assert set(truth.effect_names(rows_of(ctx, p))) == {"benign"}
