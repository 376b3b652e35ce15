"""Flow assembly: keys, direction, vantage-point de-duplication, timeouts, caps, minimum size."""

from __future__ import annotations

import numpy as np
import pytest
from pcapgen import A, B, C, http_session, ipv6_session, syn_flood, tcp, udp, write

from uavcas.flows import FlowConfig, extract_flows


def test_syn_flood_one_flow_per_source_port(tmp_path):
    pk = http_session(0.0, A, B) + syn_flood(20, t0=1.0, attacker=C, victim=B)
    path = write(tmp_path / "f.pcap", sorted(pk, key=lambda p: p.time))
    df = extract_flows([path]).frame
    flood = df[df.src_ip == C]
    assert len(flood) == 20 and set(flood.packets) == {1} and set(flood["SYN Flag Count"]) == {1.0}
    assert set(flood.dst_port) == {80} and flood.src_port.nunique() == 20
    http = df[df.src_ip == A].iloc[0]
    assert http.packets == len(http_session()) and http.src_port == 40000 and http.dst_port == 80
    # hostpair: the flood is one flow; the default min of 10 packets applies
    hp = extract_flows([path], FlowConfig(view="hostpair")).frame
    assert sorted(hp.packets.tolist()) == [len(http_session()), 20]
    assert set(hp.src_port) == {0} and set(hp.protocol) == {0}
    hp2 = extract_flows([path], FlowConfig(view="hostpair", min_packets=15)).frame
    assert hp2.packets.tolist() == [20]


def test_direction_initiator_and_synack_first(tmp_path):
    pk = http_session(0.0, A, B)[1:]  # the SYN was not captured: first packet is the SYN-ACK
    df = extract_flows([write(tmp_path / "s.pcap", pk)]).frame
    r = df.iloc[0]
    assert (r.src_ip, r.src_port, r.dst_ip, r.dst_port) == (A, 40000, B, 80)
    assert r["Total Fwd Packets"] == 4 and r["Total Backward Packets"] == len(pk) - 4
    seq_dir = np.asarray(df.seq_dir.iloc[0])
    assert seq_dir[0] == -1 and seq_dir[1] == 1
    # UDP: the first packet's sender is forward
    u = [udp(0, B, A, 53, 4000), udp(0.1, A, B, 4000, 53), udp(0.2, B, A, 53, 4000)]
    ud = extract_flows([write(tmp_path / "u.pcap", u)]).frame.iloc[0]
    assert (ud.src_ip, ud.src_port, ud["Total Fwd Packets"], ud["Total Backward Packets"]) == (B, 53, 2, 1)


def test_vantage_point_dedup(tmp_path):
    s = http_session(0.0, A, B)
    p1 = [p.copy() for p in s]
    p2 = [p.copy() for i, p in enumerate(s) if i != 5]  # this point missed one packet
    for p in p2:
        p.time += 0.0002
    w1, w2 = write(tmp_path / "s-a.pcap", p2), write(tmp_path / "s-b.pcap", p1)
    ex = extract_flows([w1, w2])
    assert len(ex.frame) == 1
    r = ex.frame.iloc[0]
    assert r.packets == len(s) and r.capture_point == "s-b"  # most packets wins over the name
    tie = extract_flows([write(tmp_path / "s-z.pcap", p1), write(tmp_path / "s-c.pcap", p1)]).frame.iloc[0]
    assert tie.capture_point == "s-c" and tie.packets == len(s)  # ties: alphabetically first
    both = extract_flows([w1, w2], FlowConfig(dedup=False)).frame.iloc[0]
    assert both.packets == 2 * len(s) - 1


def test_timeouts_and_cap(tmp_path):
    pk = [udp(t, A, B, 1000, 2000) for t in (0, 1, 2, 200, 201, 2000, 2001)]
    path = write(tmp_path / "t.pcap", pk)
    assert extract_flows([path]).frame.packets.tolist() == [7]
    idle = extract_flows([path], FlowConfig(idle_timeout_s=120)).frame
    assert idle.packets.tolist() == [3, 2, 2]
    act = extract_flows([path], FlowConfig(active_timeout_s=1.5)).frame
    assert act.packets.tolist() == [2, 1, 2, 2]
    cap = extract_flows([path], FlowConfig(max_packets=4)).frame
    assert cap.packets.tolist() == [4] and cap.duration_s.iloc[0] == pytest.approx(200)


def test_ipv6_flow(tmp_path):
    df = extract_flows([write(tmp_path / "v6.pcap", ipv6_session())]).frame
    assert len(df) == 1 and df.src_ip[0] == "2001:db8::1" and df.protocol[0] == 6
    assert df["Fwd Header Length"][0] == 3 * (40 + 20) and df["Bwd Header Length"][0] == 60


def test_mixed_flows_and_ordering(tmp_path):
    pk = sorted(http_session(0.0, A, B, 40001) + http_session(0.05, C, B, 40002) + [tcp(0.07, A, B, 7, 7, "R")], key=lambda p: p.time)
    df = extract_flows([write(tmp_path / "m.pcap", pk)]).frame
    assert len(df) == 3 and df.packets.sum() == len(pk)
    assert (df.first_ts.diff().dropna() >= 0).all()  # flows ordered by first packet
