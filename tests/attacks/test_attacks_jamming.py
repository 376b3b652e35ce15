"""The jamming family: token, SINR arithmetic, the plan's jammed overrides, determinism."""

from __future__ import annotations

import math

import numpy as np
import pytest

from uavcas.attacks import Emitter, ScenarioError
from uavcas.attacks.jamming import Jamming, JammingSpec
from uavcas.channel import Channel
from uavcas.channel.budget import link_chain
from uavcas.channel.interference import jammed_chain, received_dbm, sinr_db
from uavcas.channel.pathloss import FreeSpace
from uavcas.scenario import parse
from uavcas.twin.interference import MATERIAL_LOSS, MATERIAL_RATE_REL, material
from uavcas.twin.plan import plan

CONFIG = "jamming=20-6-2-telemetry-logdist-adaptive-grid-30-95"


# codec ---------------------------------------------------------------------------------------
@pytest.mark.parametrize("tok, eirp, duty, where", [
    ("jamming=20", 20, 100, "near"), ("jamming=0", 0, 100, "near"), ("jamming=60,5", 60, 5, "near"),
    ("jamming=20,100,uav", 20, 100, "uav"), ("jamming=33,50,uav", 33, 50, "uav"),
])
def test_token_parses_and_reads_back(tok, eirp, duty, where):
    sc = parse(f"{tok}-6-2-telemetry-logdist-adaptive-grid-30-95")
    s = sc.attacks[0]
    assert isinstance(s, JammingSpec) and (s.eirp_dbm, s.duty_pct, s.placement) == (eirp, duty, where)
    assert s.token() == tok and parse(sc.to_string()) == sc


@pytest.mark.parametrize("tok, words", [
    ("jamming", "needs an EIRP"), ("jamming=", "non-negative integer"), ("jamming=-3", "fields"),
    ("jamming=61", "outside [0, 60]"), ("jamming=20,0", "outside [1, 100]"), ("jamming=20,101", "outside"),
    ("jamming=20,50,far", "not one of near, uav"), ("jamming=20,50,uav,1", "takes <eirp_dbm>"),
    ("jamming=20,100", "canonical form ('jamming=20')"), ("jamming=20,50,near", "canonical form ('jamming=20,50')"),
    ("jamming=020", "non-negative integer"),
])
def test_bad_tokens_are_one_line_errors(tok, words):
    with pytest.raises(ScenarioError) as e:
        parse(f"{tok}-6-2-telemetry-logdist-adaptive-grid-30-95")
    assert words in str(e.value) and "\n" not in str(e.value)


def test_jamming_composes_with_the_paper_families():
    sc = parse("blackhole+jamming=20-6-2-telemetry-logdist-adaptive-grid-30-95")
    assert sc.families == ("blackhole", "jamming")
    p = plan(sc, seed=2)
    bh, jam = p.attacks
    assert jam.attackers == [] and bh.victims == jam.victims  # a ground jammer is no swarm node


# channel arithmetic ----------------------------------------------------------------------------
def test_sinr_by_the_link_budget_on_a_hand_computed_case():
    # Free space at 3.51 GHz (Friis): PL(d) = 20 log10(4 pi d f / c).
    #   link: 30 dBm TX, 300 m: PL = 92.896 dB, S = 30 - 92.896 = -62.896 dBm; N = -95 dBm
    #         -> SNR = 32.104 dB
    #   jammer: 20 dBm EIRP, 100 m from the receiver: PL = 83.354 dB, I = 20 - 83.354 = -63.354 dBm
    #   N + I = 10 log10(10^-9.5 + 10^-6.3354) mW = 10 log10(3.162e-10 + 4.6446e-7) = -63.351 dBm
    #   SINR = S - (N + I) = -62.896 - (-63.351) = 0.455 dB
    fs = FreeSpace(fc_ghz=3.51)
    rx = np.array([[100.0, 0.0, 50.0]])
    jammer = np.array([0.0, 0.0, 50.0])  # at the receiver's height: 100 m 3-D
    i_dbm = received_dbm(fs, 20.0, 0.0, jammer, False, rx, np.array([False]))
    assert i_dbm[0] == pytest.approx(-63.354, abs=0.01)
    snr = 30.0 - 92.896 - (-95.0)
    assert snr == pytest.approx(32.104, abs=0.01)
    assert sinr_db(snr, -95.0, i_dbm)[0] == pytest.approx(0.455, abs=0.01)
    # no interference power: SINR = SNR; interference at the noise floor: 3.01 dB less
    assert sinr_db(snr, -95.0, -400.0) == pytest.approx(snr, abs=1e-9)
    assert sinr_db(snr, -95.0, -95.0) == pytest.approx(snr - 3.0103, abs=0.001)


def test_one_state_mixture_is_the_link_chain_and_a_duty_cycle_averages_the_loss():
    snr = np.array([3.0, 9.0, 20.0])
    a, b = link_chain(snr, 100.0), link_chain(snr, 100.0, states=([snr], [1.0]))
    assert np.array_equal(a[0], b[0]) and np.array_equal(a[2].loss, b[2].loss)
    assert np.array_equal(a[2].mac_time_us, b[2].mac_time_us)
    # fixed MCS: a packet meets the jammer on with probability D, so the loss is the D-mixture
    on, off = link_chain(snr - 15, 100.0, fixed_mcs=2), link_chain(snr, 100.0, fixed_mcs=2)
    mix = link_chain(snr, 100.0, fixed_mcs=2, states=([snr - 15, snr], [0.3, 0.7]))
    assert np.allclose(mix[2].loss, 0.3 * on[2].loss + 0.7 * off[2].loss, rtol=1e-12, atol=0)
    assert np.allclose(mix[2].mac_time_us, 0.3 * on[2].mac_time_us + 0.7 * off[2].mac_time_us)


def test_issue_check_20_dbm_at_100_m_from_a_30_dbm_links_receiver_changes_its_mcs_or_loss():
    # one BS-UAV link at 30 dBm through the default chain (log-distance, fading, adaptive MCS)
    ch = Channel(n_nodes=2, pathloss="logdist", tx_power_dbm=30.0, noise_dbm=-95.0, seed=0)
    pos = np.array([[0.0, 0.0, 10.0], [400.0, 0.0, 60.0]])
    arr = ch.evaluate(pos, np.array([[0, 1]]), np.array([True, False]))
    jammer = np.array([400.0, 100.0, 60.0])  # 100 m from the UAV receiver, at its height
    i_dbm = received_dbm(ch.model, 20.0, 0.0, jammer, False, pos[1:], np.array([False]))
    sinr, mcs, lp = jammed_chain(ch.chain, arr.snr_db, i_dbm, 1.0, arr.distance_m, None)
    assert sinr[0] < arr.snr_db[0] - 20  # the jammer is ~30 dB above the noise floor
    assert mcs[0] != arr.mcs[0] or abs(lp.loss[0] - arr.loss[0]) >= MATERIAL_LOSS


# the plan --------------------------------------------------------------------------------------
def test_issue_check_in_the_plan_with_the_jammer_placed_100_m_from_the_victim(monkeypatch):
    """`jamming=20` placed 100 m from the receiver of links planned at 30 dBm: the plan changes
    their MCS or loss (the placement forced; everything else is the plan's own chain)."""

    def at_100_m(self, attack, ctx):
        v = ctx.positions_m[:, ctx.names.index(attack.victims[0])]
        return Emitter(v + np.array([100.0, 0.0, 0.0]), ground=False, eirp_dbm=20.0, duty=1.0)

    monkeypatch.setattr(Jamming, "emitter", at_100_m)
    p = plan(CONFIG, seed=1)
    a = p.attacks[0]
    victim = a.victims[0]
    w = p.windows[int((a.start_s + a.stop_s) / 2 // p.window_s)]
    at_victim = [o for o in w.link_overrides if o.dst == victim]
    assert at_victim, "no link received at the victim was changed"
    links = {(lk.a, lk.b): lk for lk in w.links}
    for o in at_victim:
        lk = links.get((o.src, o.dst)) or links[(o.dst, o.src)]
        assert o.mcs != lk.mcs or abs(o.loss - lk.loss) >= MATERIAL_LOSS
        assert o.sinr_db < lk.snr_db and o.interference_dbm > -95.0


def test_plan_records_the_jammer_and_jammed_vs_unjammed_links():
    p = plan(CONFIG, seed=1)
    a = p.attacks[0]
    inside = [w for w in p.windows if w.t_s < a.stop_s and w.t_s + w.duration_s > a.start_s]
    assert all(not w.interferers and not w.link_overrides for w in p.windows if w not in inside)
    first, last = inside[0], inside[-1]
    # a jammer shorter than a window: the plan marks the sub-window
    assert first.interferers[0].start_s == a.start_s and first.interferers[0].stop_s == first.t_s + first.duration_s
    assert last.interferers[0].stop_s == a.stop_s
    for w in inside:
        (jam,) = w.interferers
        assert jam.attack_id == a.attack_id and jam.eirp_dbm == 20.0 and jam.duty == 1.0 and jam.ground
        assert jam.fc_ghz == pytest.approx(3.51)  # the swarm's own carrier (the profile's)
        assert jam.position == inside[0].interferers[0].position  # a ground jammer stays put
        links = {(lk.a, lk.b): lk for lk in w.links}
        assert w.link_overrides
        for o in w.link_overrides:
            lk = links.get((o.src, o.dst)) or links[(o.dst, o.src)]
            assert lk.kind == "air" and (o.start_s, o.stop_s) == (jam.start_s, jam.stop_s)
            assert o.sinr_db == pytest.approx(sinr_db(lk.snr_db, -95.0, o.interference_dbm), abs=0.002)
            assert material(lk.mcs, lk.rate_mbps, lk.loss, o.mcs, o.rate_mbps, o.loss)
            assert o.delay_ms == lk.delay_ms  # jamming changes no propagation delay
    # the unjammed plan is the benign plan's: the jammer only adds overrides
    benign = plan(CONFIG.replace("jamming=20", "benign"), seed=1)
    assert [w.links for w in p.windows] == [w.links for w in benign.windows]
    assert any(abs(o.rate_mbps - lk.rate_mbps) >= MATERIAL_RATE_REL * lk.rate_mbps
               for w in inside for o in w.link_overrides
               for lk in w.links if {lk.a, lk.b} == {o.src, o.dst})


def test_placements_near_the_route_and_on_the_attacker_uav():
    p = plan(CONFIG, seed=4)
    a = p.attacks[0]
    w = next(w for w in p.windows if w.interferers)
    jam = w.interferers[0]
    xs = [w.positions[a.victims[0]] for w in p.windows if w.interferers]
    d = min(math.dist(jam.position[:2], v[:2]) for v in xs)
    assert d <= 120.0 + 5 * 15.0  # within the offset of a point of the route (the UAV moves <= 15 m/s)
    q = plan(CONFIG.replace("jamming=20", "jamming=20,50,uav"), seed=4)
    b = q.attacks[0]
    assert len(b.attackers) == 1 and b.attackers[0] != b.victims[0]
    for w in q.windows:
        for j in w.interferers:
            assert j.position == w.positions[b.attackers[0]] and not j.ground and j.duty == 0.5


def test_same_seed_and_config_give_the_same_plan_json():
    assert plan(CONFIG, seed=3).to_json() == plan(CONFIG, seed=3).to_json()
    a, b = plan(CONFIG, seed=3), plan(CONFIG, seed=5)
    pa = next(w.interferers[0].position for w in a.windows if w.interferers)
    pb = next(w.interferers[0].position for w in b.windows if w.interferers)
    assert pa != pb


# truth (hand-built packets: tests/helpers/hand_truth.py) -------------------------------------------
def test_truth_rule_on_hand_built_packets():
    from helpers.hand_truth import IPS, PLAN, T0, pkt, table
    from uavcas.flows.follow import Timeline, follow
    from uavcas.labels.attacklog import AttackLog, AttackWindow
    from uavcas.labels.effects import TruthContext, packet_truth
    from uavcas.twin.model import LinkOverride

    def over(src, dst, rate, loss, mcs):
        return LinkOverride(attack_id="jamming-0", src=src, dst=dst, start_s=5.0, stop_s=10.0, interference_dbm=-70.0,
                            sinr_db=5.0, mcs=mcs, rate_mbps=rate, delay_ms=0.05, loss=loss)

    # window 1 [5, 10): uav0 -> bs0 jammed (rate 50 -> 5 Mbit/s, loss 0 -> 0.3); uav0 -> uav1 only
    # changes MCS (rate -2 %, loss +0.5 pp: under both thresholds); bs0 -> uav0 not jammed
    w1 = PLAN.windows[1].model_copy(update={"link_overrides": [over("uav0", "bs0", 5.0, 0.3, 0),
                                                                over("uav0", "uav1", 49.0, 0.005, 4)]})
    plan = PLAN.model_copy(update={"windows": [PLAN.windows[0], w1, *PLAN.windows[2:]]})
    pk = [pkt(6.0, "uav0", "bs0", 1000, 80, ip_id=1),                 # crossed the jammed direction: jamming
          pkt(6.1, "uav0", "bs0", 1000, 80, ip_id=2, at=["uav0"]),    # lost on it inside: jamming
          pkt(2.0, "uav0", "bs0", 1000, 80, ip_id=3, at=["uav0"]),    # lost on it before: channel_loss
          pkt(6.2, "bs0", "uav0", 80, 1000, ip_id=4),                 # other direction: benign
          pkt(6.3, "uav0", "uav1", 1000, 80, ip_id=5),                # MCS-only direction crossed: benign
          pkt(6.4, "uav0", "uav1", 1000, 80, ip_id=6, at=["uav0"]),   # ... lost on it: jamming
          pkt(8.5, "uav0", "bs0", 1000, 80, ip_id=7)]                 # after the logged stop at 8 s: benign
    t = table(pk)
    # the jammer's logged [start, stop): 5.5-8.0 s (a ground jammer: no attacker host)
    aw = AttackWindow(attack_id="jamming-0", family="jamming", attacker_ips=(), victim_ips=(IPS["uav0"],),
                      start_unix=T0 + 5.5, stop_unix=T0 + 8.0)
    ctx = TruthContext(t, AttackLog(windows=(aw,)), follow(t, Timeline.from_plan(plan, T0)), plan, T0)
    truth = packet_truth(ctx)
    by_id = {}
    for r, e in zip(t["ip_id"].tolist(), truth.effect_names().tolist()):
        by_id.setdefault(r, set()).add(e)
    assert by_id == {1: {"jamming"}, 2: {"jamming"}, 3: {"channel_loss"}, 4: {"benign"}, 5: {"benign"},
                     6: {"jamming"}, 7: {"benign"}}
