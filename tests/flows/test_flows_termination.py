"""Termination policies on built packet sequences: connection (default), cic, timeout."""

from __future__ import annotations

import numpy as np
import pytest

from helpers.pcapgen import A, B, C, http_session, tcp, udp, write
from uavcas.flows import FlowConfig, extract_flows
from uavcas.flows.termination import CLOSE_GRACE_S

US = 1e6
CIC = FlowConfig(termination="cic")


def flows(tmp_path, pk, cfg=FlowConfig(), name="c.pcap"):
    return extract_flows([write(tmp_path / name, sorted(pk, key=lambda p: p.time))], cfg).frame


def close(t, first, second, c_seq=1019, s_seq=8001, acked=True):
    """FIN from `first`, FIN+ACK from `second`, the last ACK (A is the client, B the server)."""
    seqs = {A: (c_seq, s_seq, 40000, 80), B: (s_seq, c_seq, 80, 40000)}
    s1, peer1, sp1, dp1 = seqs[first]
    s2, peer2, sp2, dp2 = seqs[second]
    out = [tcp(t, first, second, sp1, dp1, "FA", seq=s1, ack=peer1),
           tcp(t + 0.01, second, first, sp2, dp2, "FA", seq=s2, ack=s1 + 1)]
    if acked:
        out.append(tcp(t + 0.02, first, second, sp1, dp1, "A", seq=s1 + 1, ack=s2 + 1))
    return out


def test_a_connection_is_one_flow_whoever_closes_first(tmp_path):
    s = http_session(0.0, A, B)
    df = flows(tmp_path, s)
    assert df.packets.tolist() == [len(s)] and df.src_ip.tolist() == [A]
    client_first = http_session(0.0, A, B)[:-3] + close(0.11, A, B)
    assert flows(tmp_path, client_first, name="c2.pcap").packets.tolist() == [len(client_first)]


def test_trailing_ack_and_retransmitted_fin_join_within_the_grace_period(tmp_path):
    s = http_session(0.0, A, B)
    last = s[-1]
    late = [last.copy(), s[-3].copy()]  # the last ACK again, the server's FIN retransmitted
    late[0].time, late[1].time = last.time + 0.3, last.time + 1.5
    assert flows(tmp_path, s + late).packets.tolist() == [len(s) + 2]
    # after the grace period the same packet is no part of the closed connection
    gone = last.copy()
    gone.time = last.time + CLOSE_GRACE_S + 1
    assert flows(tmp_path, s + [gone], name="g.pcap").packets.tolist() == [len(s), 1]
    shorter = flows(tmp_path, s + late, FlowConfig(grace_s=1.0), name="s.pcap")
    assert shorter.packets.tolist() == [len(s) + 1, 1]


def test_an_unacknowledged_last_fin_leaves_the_connection_open(tmp_path):
    # both FINs sent, the last one never acknowledged: open, so a later SYN-less packet still joins
    pk = http_session(0.0, A, B)[:-1]
    straggler = tcp(20.0, B, A, 80, 40000, "A", seq=8002, ack=1020)
    assert flows(tmp_path, pk + [straggler]).packets.tolist() == [len(pk), 1]  # the idle timeout (15 s) cuts
    assert flows(tmp_path, pk + [straggler], FlowConfig(idle_timeout_s=30)).packets.tolist() == [len(pk) + 1]


def test_simultaneous_close(tmp_path):
    pk = http_session(0.0, A, B)[:-3]
    pk += [tcp(0.11, A, B, 40000, 80, "FA", seq=1019, ack=8001), tcp(0.11, B, A, 80, 40000, "FA", seq=8001, ack=1019),
           tcp(0.12, A, B, 40000, 80, "A", seq=1020, ack=8002), tcp(0.12, B, A, 80, 40000, "A", seq=8002, ack=1020)]
    late = tcp(2.0, A, B, 40000, 80, "A", seq=1020, ack=8002)
    assert flows(tmp_path, pk + [late]).packets.tolist() == [len(pk) + 1]


def test_rst_closes_and_a_new_syn_after_the_close_starts_a_new_flow(tmp_path):
    first = http_session(0.0, A, B)[:5] + [tcp(0.2, A, B, 40000, 80, "R", seq=1019)]
    again = http_session(3.0, A, B)  # the client reuses its port: a new connection
    df = flows(tmp_path, first + again)
    assert df.packets.tolist() == [6, len(again)]
    # a flood SYN answered by the victim, the attacker's RST, and the SYN-ACK retransmitted 1 s
    # and 3 s later (the RST was lost) with the attacker's RSTs: one flow
    flood = [tcp(0, C, B, 2000, 80, "S", seq=7), tcp(0.001, B, C, 80, 2000, "SA", seq=90, ack=8),
             tcp(0.002, C, B, 2000, 80, "R", seq=8), tcp(1.0, B, C, 80, 2000, "SA", seq=90, ack=8),
             tcp(1.001, C, B, 2000, 80, "R", seq=8), tcp(3.0, B, C, 80, 2000, "SA", seq=90, ack=8),
             tcp(3.001, C, B, 2000, 80, "R", seq=8)]
    f = flows(tmp_path, flood, name="f.pcap")
    assert f.packets.tolist() == [7] and f.src_ip.tolist() == [C]


def test_a_syn_inside_an_established_connection_stays_in_it(tmp_path):
    # a copy of the opening SYN with another sequence number (a replayer's rewrite) injected while
    # the connection is live: the stack answers it with a challenge ACK; one connection, one flow
    s = http_session(0.0, A, B)
    inj = tcp(0.035, A, B, 40000, 80, "S", seq=4242)
    assert flows(tmp_path, s + [inj]).packets.tolist() == [len(s) + 1]
    # before the handshake completes it is a new attempt (SYN, SYN-ACK, then a new SYN)
    half = [tcp(0, C, B, 2000, 80, "S", seq=1), tcp(0.001, B, C, 80, 2000, "SA", seq=9, ack=2),
            tcp(0.5, C, B, 2000, 80, "S", seq=77)]
    assert flows(tmp_path, half, name="h.pcap").packets.tolist() == [2, 1]


def test_syn_ack_first_is_turned_to_the_syn_sender(tmp_path):
    pk = http_session(0.0, A, B)[1:]
    r = flows(tmp_path, pk).iloc[0]
    assert (r.src_ip, r.src_port, r["Total Fwd Packets"]) == (A, 40000, 4)
    c = flows(tmp_path, pk, CIC, name="cic.pcap").iloc[0]  # CICFlowMeter: the first packet's sender
    assert (c.src_ip, c.src_port) == (B, 80)


def test_new_syn_starts_a_new_flow_but_a_retransmission_does_not(tmp_path):
    pk = [tcp(0, C, B, 2000, 80, "S", seq=111), tcp(0.5, C, B, 2000, 80, "S", seq=111),  # retransmitted SYN
          tcp(3.0, C, B, 2000, 80, "S", seq=999),  # hping3 restarted on the same port: a new attempt
          tcp(3.1, B, C, 80, 2000, "SA", seq=5, ack=1000), tcp(3.2, C, B, 2000, 80, "S", seq=999)]  # fmt: skip
    assert flows(tmp_path, pk).packets.tolist() == [2, 3]
    assert flows(tmp_path, pk, FlowConfig(termination="timeout"), name="t.pcap").packets.tolist() == [5]


def test_cic_closes_at_the_first_backward_fin_and_drops_a_second_forward_fin(tmp_path):
    # server closes first (backward FIN): CICFlowMeter's flow ends there, the client's FIN and the
    # last ACK form its trailing "appendix" flow
    s = http_session(0.0, A, B)
    df = flows(tmp_path, s, CIC)
    assert df.packets.tolist() == [len(s) - 2, 2] and df.src_ip.tolist() == [A, A]
    # client closes first: its (forward) FIN closes nothing; a retransmission of it is dropped; the
    # server's FIN closes; the last ACK alone is a one-packet flow, never written
    pk = http_session(0.0, A, B)[:-3] + close(0.11, A, B)
    dup = pk[-3].copy()
    dup.time += 0.005
    df = flows(tmp_path, pk + [dup], CIC, name="d.pcap")
    assert df.packets.tolist() == [len(pk) - 1] and df["FIN Flag Count"].tolist() == [2]
    assert flows(tmp_path, pk + [dup], name="d2.pcap").packets.tolist() == [len(pk) + 1]  # connection keeps all
    # any RST closes, in either direction; the flow's first packet never does
    pk = [tcp(0, A, B, 1, 2, "S"), tcp(0.1, B, A, 2, 1, "SA"), tcp(0.2, A, B, 1, 2, "FA"), tcp(0.3, B, A, 2, 1, "A"),
          tcp(0.4, B, A, 2, 1, "R"), tcp(0.5, A, B, 1, 2, "A"), tcp(0.6, A, B, 1, 2, "R"), tcp(0.7, B, A, 2, 1, "A")]
    assert flows(tmp_path, pk, CIC, name="r.pcap").packets.tolist() == [5, 2]  # the lone last ACK is not written
    assert flows(tmp_path, [tcp(0, A, B, 1, 2, "R"), tcp(0.1, A, B, 1, 2, "R")], CIC,
                 name="r1.pcap").packets.tolist() == [2]


def test_cic_flow_timeout_keeps_the_orientation_and_counts_the_first_packet_forward(tmp_path):
    pk = [udp(0, A, B, 1, 2), udp(60, B, A, 2, 1), udp(121, B, A, 2, 1), udp(122, B, A, 2, 1), udp(123, A, B, 1, 2)]
    df = flows(tmp_path, pk, CIC)
    assert df.packets.tolist() == [2, 3]
    later = df.iloc[1]
    # FlowGenerator: new BasicFlow(packet, flow.getSrc(), ...): A stays the source, B's packet at
    # 121 s is counted forward (firstPacket), its 122 s packet backward; the row's identity is
    # CICFlowMeter's (Source IP/Port = the kept source A:1), not the first packet's sender
    assert (later.src_ip, later.src_port, later.dst_ip, later.dst_port) == (A, 1, B, 2)
    assert (later["Total Fwd Packets"], later["Total Backward Packets"]) == (2, 1)
    assert list(later.seq_dir) == [1, -1, 1]


def test_cic_all_47_features_of_a_syn_ack_first_flow_by_hand(tmp_path):
    pk = [tcp(0.000, B, A, 80, 40000, "SA", seq=5000, ack=1001), tcp(0.010, A, B, 40000, 80, "A", seq=1001, ack=5001),
          tcp(0.020, A, B, 40000, 80, "PA", b"q" * 100, seq=1001, ack=5001),
          tcp(0.050, B, A, 80, 40000, "A", b"r" * 300, seq=5001, ack=1101)]
    r = flows(tmp_path, pk, CIC).iloc[0]
    iat = np.array([10_000, 10_000, 30_000.0])
    lens = np.array([0, 0, 0, 100, 300.0])  # flowLengthStats: the first packet's payload twice
    expect = {
        "Flow Duration": 50_000, "Flow Bytes/s": 400 / 0.05, "Flow Packets/s": 4 / 0.05,
        "Flow IAT Mean": iat.mean(), "Flow IAT Std": iat.std(ddof=1), "Flow IAT Max": 30_000, "Flow IAT Min": 10_000,
        "Min Packet Length": 0, "Max Packet Length": 300, "Packet Length Mean": 80,
        "Packet Length Std": lens.std(ddof=1),
        "Packet Length Variance": 17_000, "FIN Flag Count": 0, "SYN Flag Count": 1, "RST Flag Count": 0,
        "PSH Flag Count": 1, "ACK Flag Count": 4, "URG Flag Count": 0, "CWE Flag Count": 0, "ECE Flag Count": 0,
        "Down/Up Ratio": 1, "Average Packet Size": 100, "Active Mean": 0, "Idle Mean": 0, "Idle Max": 0,
        # forward = B, the first packet's sender: the SYN-ACK and the 300-byte answer
        "Total Fwd Packets": 2, "Total Backward Packets": 2, "Total Length of Fwd Packets": 300,
        "Total Length of Bwd Packets": 100, "Fwd Packet Length Max": 300, "Fwd Packet Length Min": 0,
        "Fwd Packet Length Mean": 150, "Fwd Packet Length Std": np.std([0, 300], ddof=1),
        "Bwd Packet Length Max": 100, "Bwd Packet Length Min": 0, "Bwd Packet Length Mean": 50,
        "Bwd Packet Length Std": np.std([0, 100], ddof=1), "Fwd IAT Total": 50_000, "Fwd IAT Mean": 50_000,
        "Fwd IAT Std": 0, "Fwd IAT Max": 50_000, "Bwd IAT Total": 10_000, "Bwd IAT Mean": 10_000, "Bwd IAT Std": 0,
        "Bwd IAT Max": 10_000, "Fwd Header Length": 40, "Bwd Header Length": 40,
    }  # fmt: skip
    assert len(expect) == 47
    for k, v in expect.items():
        assert r[k] == pytest.approx(v, rel=1e-9), k
    assert r.src_ip == B


def test_timeout_policy_uses_nfstreams_timeouts(tmp_path):
    pk = [udp(t, A, B, 1000, 2000) for t in (0, 100, 219, 340)]  # gaps 100, 119, 121 s
    assert flows(tmp_path, pk, FlowConfig(termination="timeout")).packets.tolist() == [3, 1]
    s = http_session(0.0, A, B) + http_session(5.0, A, B)  # the same 5-tuple twice: no SYN rule
    assert flows(tmp_path, s, FlowConfig(termination="timeout"), name="h.pcap").packets.tolist() == [len(s)]


def test_policy_errors():
    with pytest.raises(ValueError, match="unknown termination policy 'fin'"):
        FlowConfig(termination="fin")  # type: ignore[arg-type]
    with pytest.raises(ValueError, match="hostpair view has no termination"):
        FlowConfig(view="hostpair", termination="cic")
    with pytest.raises(ValueError, match="connection policy only"):
        FlowConfig(termination="cic", grace_s=5)
    assert FlowConfig().describe()["termination"] == "connection" and FlowConfig().describe()["close_grace_s"] == 60
    assert FlowConfig(termination="cic").effective_min_packets == 2


@pytest.mark.slow  # 7 s on 2 cores
def test_spoofed_syn_flood_one_flow_per_attempt(tmp_path):
    # random spoofed sources and ports, some 5-tuples drawn twice with new sequence numbers: every
    # attempt is a flow, whatever the policy that ends TCP connections
    rng = np.random.default_rng(5)
    n = 3000
    src = [f"10.{int(a)}.{int(b)}.1" for a, b in rng.integers(0, 4, size=(n, 2))]
    sport = rng.integers(1024, 1100, size=n)
    pk = [tcp(0.001 * k, src[k], B, int(sport[k]), 80, "S", seq=int(rng.integers(1, 2**31))) for k in range(n)]
    distinct = len(set(zip(src, sport.tolist())))
    assert distinct < n  # some 5-tuples recur
    assert len(flows(tmp_path, pk)) == n
    assert len(flows(tmp_path, pk, FlowConfig(termination="timeout"), name="t.pcap")) == distinct
