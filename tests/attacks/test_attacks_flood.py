"""DoS / DDoS: token, schedule rule, calibration times, packet-exact ground truth."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from synth_run import DOS_WINDOW, IPS, N_FLOOD, T0

from uavcas.attacks import ScenarioError, ScheduleDraw, family
from uavcas.attacks.flood import FloodSpec
from uavcas.scenario import parse


def test_token_and_typed_params():
    spec = family("dos").parse("250", "dos=250")
    assert spec == FloodSpec(family="dos", interval_us=250) and spec.nominal_pps == 4000.0
    assert family("dos").params(spec) == {"interval_us": 250, "nominal_pps": 4000.0}
    assert family("ddos").spec_from_params({"nominal_pps": 2000.0}).interval_us == 500
    with pytest.raises(ScenarioError, match="needs an interval"):
        family("ddos").parse(None, "ddos")
    with pytest.raises(ScenarioError, match="attacks.dos"):
        family("dos").parse("0", "dos=0")


def test_ddos_takes_two_up_to_a_third_of_the_swarm():
    names = [f"uav{i}" for i in range(13)]  # (13 - 1) // 3 = 4 attackers at most
    counts = set()
    for seed in range(40):
        rng = np.random.default_rng(seed)
        pool = [n for n in rng.permutation(names).tolist() if n != "uav0"]
        got = family("ddos").attackers(FloodSpec(family="ddos", interval_us=1000),
                                       ScheduleDraw(names, "uav0", pool, None, rng))
        assert "uav0" not in got and got == sorted(got, key=names.index)
        counts.add(len(got))
    assert counts == {2, 3, 4}
    assert family("dos").attackers(FloodSpec(family="dos", interval_us=1000),
                                   ScheduleDraw(names, "uav0", names[1:], None, np.random.default_rng(0))) == ["uav1"]


def test_ddos_needs_three_uavs():
    with pytest.raises(ScenarioError, match="ddos needs at least 3"):
        parse("ddos=1000-2-1-image-logdist-adaptive-grid-30-95")


def test_pacing_follows_the_token_down_to_the_floor_and_needs_no_calibration():
    from uavcas.emulation.apps.flood import PACE_FLOOR_US, pace_interval_us
    from uavcas.twin.model import Attack

    for token, interval in (("dos=1000", 1000), ("ddos=250", 250), ("dos=10", PACE_FLOOR_US)):
        spec = parse(f"{token}-3-1-image-logdist-adaptive-grid-30-95").attacks[0]
        assert pace_interval_us(spec.nominal_pps) == interval
        att = Attack(attack_id="dos-0", family=spec.family, attackers=["uav1"], victims=["uav0"], start_s=2.0,
                     stop_s=6.0, spec=spec)
        assert family(spec.family).calibration_times(att) == []  # one hping3, paced, never restarted


def test_effect_is_packet_exact_inside_the_window(truth_ctx):
    (w,) = truth_ctx.log.of_family("dos")
    hits = family("dos").effects(truth_ctx, [w])
    p = truth_ctx.packets.to_pandas()[hits]
    assert len(p) == N_FLOOD and (p.src_ip == IPS["uav1"]).all() and (p.dst_ip == IPS["uav0"]).all()
    assert ((p.tcp_flags & 0x12) == 0x02).all()
    assert (p.ts_s >= T0 + DOS_WINDOW[0]).all() and (p.ts_s < T0 + DOS_WINDOW[1]).all()
    later = dataclasses.replace(w, start_unix=w.stop_unix, stop_unix=w.stop_unix + 10)
    assert not family("dos").effects(truth_ctx, [later]).any()  # same host pair, outside the window
    wrong_way = dataclasses.replace(w, attacker_ips=w.victim_ips, victim_ips=w.attacker_ips)
    assert not family("dos").effects(truth_ctx, [wrong_way]).any()  # SYN-ACKs alone are no flood
