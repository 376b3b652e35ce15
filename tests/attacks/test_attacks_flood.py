"""DoS / DDoS: token, schedule rule, calibration times, packet-exact ground truth."""

from __future__ import annotations

import dataclasses

import numpy as np
import pandas as pd
import pytest

from helpers.synth_run import DOS_WINDOW, IPS, N_FLOOD, T0
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
    from uavcas.attacks.tools.flood import PACE_FLOOR_US, pace_interval_us
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


# Provoked packets (hand-built tables, tests/helpers/hand_truth.py): uav1 floods uav0:80 in [20, 30).
def _flood_run():
    from helpers.hand_truth import ACK, RST, SYN, icmp_error, pkt

    syn = pkt(21.0, "uav1", "uav0", 1500, 80, SYN, seq=1000, ip_id=1)
    other = pkt(21.5, "uav1", "uav0", 1501, 81, SYN, seq=0xFFFFFFFF, ip_id=2)  # seq + 1 wraps to 0
    p = {
        "syn": syn, "other": other,
        "synack": pkt(21.001, "uav0", "uav1", 80, 1500, SYN | ACK, seq=5000, ack=1001, ip_id=11),
        "rst": pkt(21.002, "uav1", "uav0", 1500, 80, RST, seq=1001, ip_id=12),
        "retx": pkt(22.001, "uav0", "uav1", 80, 1500, SYN | ACK, seq=5000, ack=1001, ip_id=13),
        # the fifth retransmission, 31 s after the first SYN-ACK: long after the attack's stop
        "late": pkt(52.001, "uav0", "uav1", 80, 1500, SYN | ACK, seq=5000, ack=1001, ip_id=14),
        # a retransmission lost on the uav0 - uav1 link (seen at the victim's switch only)
        "lost": pkt(24.001, "uav0", "uav1", 80, 1500, SYN | ACK, seq=5000, ack=1001, ip_id=15, at=["uav0"]),
        "wrapped": pkt(21.501, "uav0", "uav1", 81, 1501, SYN | ACK, seq=6000, ack=0, ip_id=16),
        # the same 5-tuple, an ack that answers no flood SYN: benign
        "wrong_ack": pkt(23.0, "uav0", "uav1", 80, 1500, SYN | ACK, seq=5000, ack=4242, ip_id=17),
        "wrong_rst": pkt(23.1, "uav1", "uav0", 1500, 80, RST, seq=999, ip_id=18),
        # a benign connection between the same hosts in the window: uav1's SYN left before the start
        "benign_syn": pkt(19.99, "uav1", "uav0", 2000, 80, SYN, seq=300, ip_id=19),
        "benign_synack": pkt(20.01, "uav0", "uav1", 80, 2000, SYN | ACK, seq=700, ack=301, ip_id=20),
        # the victim answers a flood SYN on a closed port with an ICMP error quoting it
        "icmp": icmp_error(21.6, "uav0", "uav1", other, ip_id=21),
        "icmp_other": icmp_error(21.7, "uav0", "uav1", dict(other, seq=123), ip_id=22),
        # an answer that came before the SYN (its ports and ack match): no answer
        "before": pkt(20.5, "uav0", "uav1", 80, 1500, SYN | ACK, seq=5000, ack=1001, ip_id=23),
    }
    return p


@pytest.mark.parametrize("fam", ["dos", "ddos"])
def test_flood_provokes_synacks_their_retransmissions_the_rst_and_icmp_errors(fam):
    from helpers.hand_truth import context, rows_of, window
    from uavcas.labels.effects import packet_truth
    from uavcas.vocabulary import FAMILIES

    p = _flood_run()
    ctx = context(list(p.values()), [window(fam, "uav1", "uav0", 20.0, 30.0)])
    truth = packet_truth(ctx)

    def effects(name):
        rows = rows_of(ctx, p[name])
        return set(truth.effect_names(rows)), set(truth.family[rows].tolist())

    k = FAMILIES.index(fam)
    assert effects("syn") == effects("other") == ({"flood"}, {k})
    for name in ("synack", "rst", "retx", "late", "lost", "wrapped", "icmp"):
        assert effects(name) == ({"provoked"}, {k}), name
    for name in ("wrong_ack", "wrong_rst", "benign_syn", "benign_synack", "icmp_other", "before"):
        assert effects(name) == ({"benign"}, {-1}), name
    # the lost retransmission is a channel loss when nothing provoked it
    assert set(packet_truth(context([p["lost"]], [window(fam, "uav1", "uav0", 20.0, 30.0)])).effect_names()) == {
        "channel_loss"}
    # the hook itself: only rows outside `made`, and nothing without flood SYNs
    made = family(fam).effects(ctx, ctx.log.of_family(fam))
    prov = family(fam).provoked(ctx, ctx.log.of_family(fam), made)
    assert not (prov & made).any() and prov.sum() == sum(len(p[n]["at"]) for n in
                                                         ("synack", "rst", "retx", "late", "lost", "wrapped", "icmp"))
    assert not family(fam).provoked(ctx, [], np.zeros(ctx.n, dtype=bool)).any()


def test_provoked_beyond_the_bound_is_benign():
    from helpers.hand_truth import ACK, SYN, context, pkt, rows_of, window
    from uavcas.attacks.answers import ANSWER_WITHIN_S
    from uavcas.labels.effects import packet_truth

    syn = pkt(21.0, "uav1", "uav0", 1500, 80, SYN, seq=1000, ip_id=1)
    far = pkt(21.0 + ANSWER_WITHIN_S + 1.0, "uav0", "uav1", 80, 1500, SYN | ACK, seq=5000, ack=1001, ip_id=2)
    ctx = context([syn, far], [window("dos", "uav1", "uav0", 20.0, 30.0)])
    assert set(packet_truth(ctx).effect_names(rows_of(ctx, far))) == {"benign"}


def test_a_blackhole_drop_of_a_provoked_synack_shows_the_blackhole_and_the_flow_both_families():
    """Blackhole+DoS on uav0: the blackhole starts at 25 s; a SYN-ACK the victim sends then is
    dropped at its switch: it shows the blackhole, its flow holds the flood SYN too."""
    from helpers.hand_truth import ACK, SYN, context, pkt, rows_of, window
    from uavcas.flows import FlowConfig
    from uavcas.flows.assemble import assemble
    from uavcas.labels.effects import packet_truth
    from uavcas.labels.label import label_flows

    syn = pkt(24.9, "uav1", "uav0", 1500, 80, SYN, seq=1000, ip_id=1)
    synack = pkt(24.901, "uav0", "uav1", 80, 1500, SYN | ACK, seq=5000, ack=1001, ip_id=2)
    dropped = pkt(25.901, "uav0", "uav1", 80, 1500, SYN | ACK, seq=5000, ack=1001, ip_id=3, at=["uav0"])
    ctx = context([syn, synack, dropped], [window("dos", "uav1", "uav0", 20.0, 30.0),
                                            window("blackhole", "uav2", "uav0", 25.0, 30.0)])
    truth = packet_truth(ctx)
    assert set(truth.effect_names(rows_of(ctx, synack))) == {"provoked"}
    assert set(truth.effect_names(rows_of(ctx, dropped))) == {"blackhole"}
    fl = assemble(ctx.packets, FlowConfig(view="5tuple"))
    frame = pd.DataFrame({"flow_id": np.arange(fl.n_flows)})
    (row,) = label_flows(fl, frame, ctx.log, truth).frame.itertuples()
    assert row.label == "Blackhole+DoS" and row.attack_packets == 3 and row.provoked_packets == 1
    assert row.attack_packets_dos == 2 and row.attack_packets_blackhole == 1
