"""Replay: token, defaults of older plans, the port mirror, packet-exact injection truth."""

from __future__ import annotations

import dataclasses

import pytest
from synth_run import IPS

from uavcas.attacks import ScenarioError, family
from uavcas.attacks.replay import MATCH_TOLERANCE_S, ReplaySpec, injected_packets, mirror_lines
from uavcas.labels import AttackLog


def test_token_and_older_plan_defaults():
    spec = family("replay").parse("100,100,20,3,rand", "replay=100,100,20,3,rand")
    assert spec == ReplaySpec(buffer_pkts=100, delay_ms=100, rate_pps=20, ttl_dec=3, seq_mode="rand")
    assert family("replay").spec_from_params({}).token() == "replay=50,200,10,5,inc"  # the paper's conservative one
    with pytest.raises(ScenarioError, match="replay needs 5"):
        family("replay").parse(None, "replay")
    with pytest.raises(ScenarioError, match="seq_mode"):
        family("replay").parse("1,2,3,4,up", "replay=1,2,3,4,up")


def test_mirror_copies_both_directions_of_the_victims_port():
    lines = mirror_lines("h2", "h1")
    assert lines[0] == "qdisc replace dev h2 clsact"
    assert any("ingress" in x and "mirror dev h1" in x for x in lines)
    assert any("egress" in x and "mirror dev h1" in x for x in lines)


def test_effect_matches_each_injection_within_the_tolerance(truth_ctx):
    log = truth_ctx.log
    assert len(log.injections) == 3
    hits = family("replay").effects(truth_ctx, log.of_family("replay"))
    p = truth_ctx.packets.to_pandas()[hits]
    assert len(p) == 3 and (p.src_ip == IPS["uav3"]).all() and (p.dst_ip == IPS["bs0"]).all()  # the copies
    assert (p.ttl == 64 - 5).all()
    assert injected_packets(truth_ctx.packets, log).sum() == 3
    late = AttackLog(log.windows, tuple(dataclasses.replace(i, t_unix=i.t_unix + 2 * MATCH_TOLERANCE_S)
                                        for i in log.injections))
    assert injected_packets(truth_ctx.packets, late).sum() == 0
    other_ttl = AttackLog(log.windows, tuple(dataclasses.replace(i, ttl=i.ttl + 1) for i in log.injections))
    assert injected_packets(truth_ctx.packets, other_ttl).sum() == 0
