"""Replay: token, defaults of older plans, the port mirror, packet-exact injection truth."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from helpers.synth_run import IPS
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


# Provoked packets (hand-built tables, tests/helpers/hand_truth.py): uav2 replays uav3's traffic in
# [10, 20); copies leave uav2's switch with TTL - 5 (and seq + k for TCP).
def _replay_run():
    from helpers.hand_truth import ACK, PSH, RST, SYN, icmp_error, pkt

    via = ["uav2", "bs0", "uav3"]  # a copy for uav3 enters at the replayer's switch
    orig_syn = pkt(12.0, "bs0", "uav3", 41000, 80, SYN, seq=5000, ip_id=100)
    copy_syn = pkt(13.0, "bs0", "uav3", 41000, 80, SYN, seq=5003, ip_id=100, ttl=59, at=via)
    closed_syn = pkt(13.5, "bs0", "uav3", 41009, 81, SYN, seq=800, ip_id=101, ttl=59, at=via)
    copy_data = pkt(14.0, "uav3", "bs0", 80, 41001, PSH | ACK, seq=9002, ack=5026, ip_id=200, ttl=59, payload=1000,
                    at=["uav2", "bs0"])
    copy_live = pkt(15.0, "bs0", "uav3", 41002, 80, PSH | ACK, seq=5002, ack=9001, ip_id=300, ttl=59, payload=24,
                    at=via)
    copy_quiet = pkt(16.0, "bs0", "uav3", 41003, 80, PSH | ACK, seq=5002, ack=9001, ip_id=400, ttl=59, payload=24,
                     at=via)
    udp_orig = pkt(16.9999, "bs0", "uav3", 5000, 6000, proto=17, ip_id=500, payload=100)
    udp_copy = pkt(17.0, "bs0", "uav3", 5000, 6000, proto=17, ip_id=500, ttl=59, payload=100, at=via)
    t_in = 2 * 50e-6  # the copy reaches uav3's switch two hops after leaving uav2's
    p = {
        "orig_syn": orig_syn, "copy_syn": copy_syn, "closed_syn": closed_syn, "copy_data": copy_data,
        "copy_live": copy_live, "copy_quiet": copy_quiet, "udp_orig": udp_orig, "udp_copy": udp_copy,
        # the original handshake's SYN-ACK and its retransmission after the copy: ack 5001, not 5004
        "orig_synack": pkt(12.01, "uav3", "bs0", 80, 41000, SYN | ACK, seq=9000, ack=5001, ip_id=1),
        "orig_retx": pkt(13.2, "uav3", "bs0", 80, 41000, SYN | ACK, seq=9000, ack=5001, ip_id=2),
        # (a) the copied SYN's SYN-ACK, and bs0's RST to it (bs0 never sent that SYN)
        "synack": pkt(13.0 + t_in + 1e-4, "uav3", "bs0", 80, 41000, SYN | ACK, seq=7000, ack=5004, ip_id=3),
        "synack_rst": pkt(13.01, "bs0", "uav3", 41000, 80, RST, seq=5004, ip_id=102),
        # (b) a copied SYN to a closed port: RST|ACK with ack = seq + 1
        "closed_rst": pkt(13.5 + t_in + 1e-4, "uav3", "bs0", 81, 41009, RST | ACK, seq=0, ack=801, ip_id=4),
        # (b) bs0's connection 41001 is closed: it resets the copied segment, seq = the copy's ack
        "data_rst": pkt(14.001, "bs0", "uav3", 41001, 80, RST, seq=5026, ip_id=103),
        # (d) connection 41002 is live: uav3's immediate duplicate ACK ...
        "dup_ack": pkt(15.0 + t_in + 1e-4, "uav3", "bs0", 80, 41002, ACK, seq=9001, ack=5026, ip_id=5),
        # ... then bs0's genuine next segment and uav3's ACK of it: benign
        "genuine": pkt(15.5, "bs0", "uav3", 41002, 80, PSH | ACK, seq=5026, ack=9001, ip_id=301, payload=24),
        "genuine_ack": pkt(15.51, "uav3", "bs0", 80, 41002, ACK, seq=9001, ack=5050, ip_id=6),
        # a reverse pure ACK long after the last copy (a keep-alive): benign
        "late_ack": pkt(19.0, "uav3", "bs0", 80, 41003, ACK, seq=9001, ack=5026, ip_id=7),
        # (c) an ICMP port unreachable quoting the copied datagram (its IP id and TTL) ...
        "icmp": icmp_error(17.0 + t_in + 1e-4, "uav3", "bs0", udp_copy, ip_id=8),
        # ... and one quoting the original (TTL 64), sent after the copy left: benign
        "icmp_orig": icmp_error(17.0003, "uav3", "bs0", udp_orig, ip_id=9),
    }
    return p


def test_replay_provokes_answers_to_its_copies():
    from helpers.hand_truth import context, injection, rows_of, window
    from uavcas.labels.effects import packet_truth
    from uavcas.vocabulary import FAMILIES

    p = _replay_run()
    copies = ("copy_syn", "closed_syn", "copy_data", "copy_live", "copy_quiet", "udp_copy")
    ctx = context(list(p.values()), [window("replay", "uav2", "uav3", 10.0, 20.0)], [injection(p[c]) for c in copies])
    truth = packet_truth(ctx)
    k = FAMILIES.index("replay")

    def effects(name):
        rows = rows_of(ctx, p[name])
        return set(truth.effect_names(rows)), set(truth.family[rows].tolist())

    for name in copies:
        assert effects(name) == ({"replay"}, {k}), name
    for name in ("synack", "synack_rst", "closed_rst", "data_rst", "dup_ack", "icmp"):
        assert effects(name) == ({"provoked"}, {k}), name
    for name in ("orig_syn", "orig_synack", "orig_retx", "genuine", "genuine_ack", "late_ack", "udp_orig", "icmp_orig"):
        assert effects(name) == ({"benign"}, {-1}), name


def test_dup_ack_needs_the_copy_to_be_the_nearest_earlier_packet_at_its_capture_point():
    """The genuine segment arriving between the copy and the ACK makes the ACK its answer."""
    from helpers.hand_truth import context, injection, rows_of, window
    from uavcas.labels.effects import packet_truth

    p = _replay_run()
    # leaves bs0's switch after the copy passed it and reaches uav3's just before the ACK leaves
    between = dict(p["genuine"], t=p["dup_ack"]["t"] - 7e-5, ip_id=999)
    ctx = context([p["copy_live"], between, p["dup_ack"]], [window("replay", "uav2", "uav3", 10.0, 20.0)],
                  [injection(p["copy_live"])])
    assert set(packet_truth(ctx).effect_names(rows_of(ctx, p["dup_ack"]))) == {"benign"}
    # the same ACK, when the segment comes after it at uav3's switch, answers the copy (it is also
    # seen at bs0's switch after the segment there: only the ACK's first capture point decides)
    later = dict(between, t=p["dup_ack"]["t"] - 1e-5)
    ctx = context([p["copy_live"], later, p["dup_ack"]], [window("replay", "uav2", "uav3", 10.0, 20.0)],
                  [injection(p["copy_live"])])
    assert set(packet_truth(ctx).effect_names(rows_of(ctx, p["dup_ack"]))) == {"provoked"}
    # the segment between copy and ACK at uav3's switch, missed by bs0's capture: at bs0's switch
    # the copy is the ACK's nearest earlier packet, but only the ACK's first point decides
    missed = dict(between, t=p["dup_ack"]["t"] - 2e-5, at=["uav3"])
    ctx = context([p["copy_live"], missed, p["dup_ack"]], [window("replay", "uav2", "uav3", 10.0, 20.0)],
                  [injection(p["copy_live"])])
    assert set(packet_truth(ctx).effect_names(rows_of(ctx, p["dup_ack"]))) == {"benign"}


def test_udp_copies_match_on_ports_and_the_nearest_transmission():
    """A MAVLink stream (unconnected UDP: IP id 0) replayed with the TTL left as it was (ttl_dec 0):
    the copies and the originals around them share addresses, ports, IP id and TTL; each record
    marks its own copy only, and a record of another port pair marks nothing of this stream."""
    from helpers.hand_truth import injection, table

    stream = [pkt_udp(12.0 + 0.1 * k) for k in range(10)]  # uav3 -> bs0:14550 at 10 Hz
    copies = [pkt_udp(12.25, at=["uav2", "bs0"]), pkt_udp(12.35, at=["uav2", "bs0"])]  # 200 ms + jitter later
    video = pkt_udp(12.45, dport=5600, at=["uav2", "bs0"])  # a copy of the video stream, same IP id and TTL
    t = table(stream + copies + [video])
    log = AttackLog((), tuple(injection(c) for c in copies))
    hit = injected_packets(t, log)
    # each record marks the copy's observation nearest its time: the first, at the replayer's switch
    first = [_rows(t, c) & (t["point"] == t.points.index("s-uav2")) for c in copies]
    assert hit.sum() == 2 and all((hit & f).sum() == 1 for f in first)
    # a record of port 5600 finds the video copy, not the MAVLink ones; one without ports (an older
    # log) still finds its copy by time
    other = dataclasses.replace(injection(copies[0]), dst_port=5600)
    got = injected_packets(t, AttackLog((), (other,)))
    assert got.sum() == 1 and (got & _rows(t, video)).sum() == 1
    unported = dataclasses.replace(injection(copies[1]), src_port=None, dst_port=None)
    got = injected_packets(t, AttackLog((), (unported,)))
    assert got.sum() == 1 and (got & first[1]).sum() == 1


def test_udp_copy_effect_covers_its_transmission():
    """With the paper's TTL decrement the copy is its own transmission: both its observations are
    `replay`, the stream's datagrams stay benign."""
    from helpers.hand_truth import context, injection, rows_of, window
    from uavcas.labels.effects import packet_truth

    stream = [pkt_udp(12.0 + 0.1 * k) for k in range(10)]
    copy = pkt_udp(12.25, ttl=59, at=["uav2", "bs0"])
    ctx = context(stream + [copy], [window("replay", "uav2", "uav3", 10.0, 20.0)], [injection(copy)])
    truth = packet_truth(ctx)
    assert set(truth.effect_names(rows_of(ctx, copy))) == {"replay"}
    assert rows_of(ctx, copy).sum() == 2
    for o in stream:
        assert set(truth.effect_names(rows_of(ctx, o))) == {"benign"}


def _rows(t, p):
    from helpers.hand_truth import HOP_S, T0

    near = np.abs(t["ts_s"] - (T0 + p["t"])) < 0.5e-3 + len(p["at"]) * HOP_S
    return near & (t["dport"] == p["dport"]) & (t["ttl"] == p["ttl"]) & (t["proto"] == p["proto"])


def pkt_udp(t, dport=14550, ttl=64, at=None):
    from helpers.hand_truth import pkt

    return pkt(t, "uav3", "bs0", 14555, dport, proto=17, ip_id=0, ttl=ttl, payload=40, at=at)
