"""GPS spoofing: the token, the seeded lure, the executor's published times, and the truth on position reports."""

from __future__ import annotations

import json
import re

import numpy as np
import pytest

from helpers.hand_truth import HOP_S, IPS, T0, context, pkt
from uavcas.attacks import ScenarioError, family
from uavcas.attacks.gps_spoof import DEFAULT_DRIFT_MPS, LURE_MAX_M, LURE_MIN_M, GpsSpoofSpec
from uavcas.labels.attacklog import AttackWindow
from uavcas.labels.effects import packet_truth
from uavcas.scenario import parse
from uavcas.twin.plan import plan
from uavcas.vocabulary import EFFECTS, FAMILIES

CFG = "gps_spoof={drift}-6-2-{payload}-logdist-adaptive-random-30-95"
GPI, GRI, HB = 33, 24, 0  # GLOBAL_POSITION_INT, GPS_RAW_INT, HEARTBEAT (MAVLink common.xml ids)


@pytest.mark.parametrize("drift,value", [("3", 3.0), ("0.5", 0.5), ("12.25", 12.25), ("100", 100.0)])
def test_token_round_trip(drift, value):
    sc = parse(CFG.format(drift=drift, payload="telemetry"))
    (spec,) = sc.attacks
    assert spec == GpsSpoofSpec(drift_mps=value) and spec.token() == f"gps_spoof={drift}"
    assert sc.to_string() == CFG.format(drift=drift, payload="telemetry")


@pytest.mark.parametrize("tok,msg", [
    ("gps_spoof", "needs a drift rate in m/s, e.g. gps_spoof=3"),
    ("gps_spoof=0", "in (0, 100]"),
    ("gps_spoof=101", "in (0, 100]"),
    ("gps_spoof=1e1", "got '1e1'"),
    ("gps_spoof=1.234", "at most two decimals"),
    ("gps_spoof=fast", "got 'fast'"),
    ("gps_spoof=3.0", "not in canonical form ('gps_spoof=3')"),
    ("gps_spoof=03", "got '03'"),
])  # fmt: skip
def test_bad_tokens_are_one_line_errors(tok, msg):
    with pytest.raises(ScenarioError, match=re.escape(msg)) as e:
        parse(f"{tok}-6-2-telemetry-logdist-adaptive-random-30-95")
    assert "\n" not in str(e.value)


def test_image_payload_is_refused_in_one_line():
    for payload in ("telemetry", "video", "mixed"):
        parse(CFG.format(drift=3, payload=payload))
    with pytest.raises(ScenarioError,
                       match="field 'payload': gps_spoof needs payload telemetry or video or mixed") as e:
        parse(CFG.format(drift=3, payload="image"))
    assert "\n" not in str(e.value) and "got 'image'" in str(e.value)
    with pytest.raises(ScenarioError, match="field 'payload'"):  # in a composition too
        parse("blackhole+gps_spoof=3-6-2-image-logdist-adaptive-random-30-95")


def test_plan_is_seeded_the_lure_recorded_and_no_attacker_node():
    cfg = CFG.format(drift=3, payload="telemetry")
    a, b = plan(cfg, seed=14, windows=4), plan(cfg, seed=14, windows=4)
    assert a.to_json() == b.to_json()  # bit for bit
    (att,) = a.attacks
    assert att.attackers == [] and len(att.victims) == 1 and att.spec == GpsSpoofSpec(drift_mps=3.0)
    assert set(att.params) == {"drift_mps", "lure_bearing_deg", "lure_distance_m"}
    assert 0 <= att.params["lure_bearing_deg"] < 360 and LURE_MIN_M <= att.params["lure_distance_m"] <= LURE_MAX_M
    lures = {tuple(plan(cfg, seed=s, windows=4).attacks[0].params.values()) for s in range(6)}
    assert len(lures) == 6  # the seed draws the lure
    # a plan written without the spec reads the default rate back
    assert family("gps_spoof").spec_from_params({}) == GpsSpoofSpec(drift_mps=DEFAULT_DRIFT_MPS)


def test_composition_plans_keep_the_other_familys_attackers():
    p = plan("blackhole+gps_spoof=3-6-2-mixed-logdist-adaptive-random-30-95", seed=3, windows=4)
    bh, gs = p.attacks
    assert bh.family == "blackhole" and len(bh.attackers) == 1 and gs.attackers == []
    assert bh.victims == gs.victims and (bh.start_s, bh.stop_s) == (gs.start_s, gs.stop_s)


def test_executor_logs_exactly_the_times_it_publishes(tmp_path):
    from uavcas.emulation.attacks import AttackExecutor
    from uavcas.traffic.mavlink.gps import Spoofing, control_path

    p = plan(CFG.format(drift=3, payload="telemetry"), seed=14, windows=4)
    (att,) = p.attacks
    ex = AttackExecutor(None, p, tmp_path, p.duration_s)  # the family touches no network
    start = ex.start(att)
    path = control_path(tmp_path, att.victims[0])
    published = Spoofing.model_validate_json(path.read_text())
    assert published.start_unix == start.t_unix and published.stop_unix is None
    assert (published.drift_mps, published.bearing_deg, published.distance_m) == (
        3.0, att.params["lure_bearing_deg"], att.params["lure_distance_m"])
    assert start.attackers == [] and start.victim_ips == [p.node(att.victims[0]).ip]
    assert start.params["lure_bearing_deg"] == att.params["lure_bearing_deg"]
    stop = ex.stop(att)
    after = json.loads(path.read_text())
    assert after["start_unix"] == start.t_unix and after["stop_unix"] == stop.t_unix > start.t_unix


def _window(start_s=10.0, stop_s=20.0, victim="uav2"):
    return AttackWindow(attack_id="gps_spoof-0", family="gps_spoof", attacker_ips=(), victim_ips=(IPS[victim],),
                        start_unix=T0 + start_s, stop_unix=T0 + stop_s)


def test_truth_marks_exactly_the_victims_position_reports_first_seen_inside_the_window():
    mav = dict(proto=17, sport=40000, dport=14550)
    spoofed = [pkt(10.0, "uav2", "bs0", mav_msgid=GPI, **mav), pkt(12.5, "uav2", "bs0", mav_msgid=GRI, **mav),
               # first seen at the victim's switch just before the stop, at the BS's after it: still spoofed
               pkt(20.0 - HOP_S / 2, "uav2", "bs0", mav_msgid=GPI, **mav)]
    benign = [pkt(9.999, "uav2", "bs0", mav_msgid=GPI, **mav),  # before the start
              pkt(20.0, "uav2", "bs0", mav_msgid=GRI, **mav),  # at the stop: re-acquired
              pkt(15.0, "uav2", "bs0", mav_msgid=HB, **mav),  # the victim's heartbeat
              pkt(15.1, "uav3", "bs0", mav_msgid=GPI, **mav),  # another UAV's report
              pkt(15.2, "bs0", "uav2", mav_msgid=GPI, proto=17, sport=14550, dport=40000),  # to the victim
              pkt(15.3, "uav2", "bs0", proto=17, sport=40002, dport=5600)]  # its video: no MAVLink
    ctx = context(spoofed + benign, [_window()])
    truth = packet_truth(ctx)
    names = truth.effect_names()
    n_spoofed = 2 * len(spoofed)  # each seen at the victim's switch and at the BS's
    assert list(names[:n_spoofed]) == ["gps_spoof"] * n_spoofed
    assert set(names[n_spoofed:]) == {"benign"}
    assert (truth.family[:n_spoofed] == FAMILIES.index("gps_spoof")).all() and (truth.family[n_spoofed:] == -1).all()
    made = truth.effect == EFFECTS.index("gps_spoof")
    assert not family("gps_spoof").provoked(ctx, [_window()], made).any()  # provoked: nothing


def test_truth_without_the_window_is_benign_and_the_rule_text_names_the_messages():
    ctx = context([pkt(15.0, "uav2", "bs0", proto=17, sport=40000, dport=14550, mav_msgid=GPI)], [])
    assert set(packet_truth(ctx).effect_names()) == {"benign"}
    f = family("gps_spoof")
    assert "GLOBAL_POSITION_INT" in f.truth_rule and "GPS_RAW_INT" in f.truth_rule and f.effect == "gps_spoof"
    assert np.array_equal(f.effects(ctx, [_window(victim="uav3")]), np.zeros(ctx.n, dtype=bool))
