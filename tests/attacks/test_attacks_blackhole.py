"""Blackhole: the relay credited with the drop, the nft table on the victim's switch, victim-window truth."""

from __future__ import annotations

import dataclasses

import numpy as np
from synth_run import BLACKHOLE_WINDOW, IPS, T0

from uavcas.attacks import ScheduleDraw, family
from uavcas.attacks.blackhole import BlackholeSpec, ruleset, switch_ports, table_name

NAMES = [f"uav{i}" for i in range(5)]


def _draw(routes0, used=()):
    d = ScheduleDraw(NAMES, "uav0", ["uav3", "uav1", "uav2", "uav4"], routes0, np.random.default_rng(0))
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


def test_truth_is_the_victims_flows_overlapping_the_window(truth_ctx):
    (w,) = truth_ctx.log.of_family("blackhole")
    f = truth_ctx.frame[family("blackhole").truth(truth_ctx, [w])]
    assert len(f) >= 1
    assert ((f.src_ip == IPS["uav3"]) | (f.dst_ip == IPS["uav3"])).all()
    assert ((f.first_ts < T0 + BLACKHOLE_WINDOW[1]) & (f.last_ts >= T0 + BLACKHOLE_WINDOW[0])).all()
    empty = dataclasses.replace(w, start_unix=T0 + 1000, stop_unix=T0 + 1001)
    assert not family("blackhole").truth(truth_ctx, [empty]).any()
