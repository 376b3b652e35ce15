"""Flow assembly: keys, direction, vantage-point de-duplication, termination, caps, numbering."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest
from scapy.layers.inet import IP

from helpers.pcapgen import A, B, C, http_session, ipv6_session, syn_flood, tcp, udp, write
from uavcas.flows import FlowConfig, StreamReport, extract_flows, flows_of, iter_flow_frames, read_packets

# one flow per key: the paper's granularity, used where a test is about keys, not termination
WHOLE = dict(termination="timeout", idle_timeout_s=0, active_timeout_s=0)
# CICFlowMeter's own segmentation: FIN/RST and its 120 s flow timeout only
CIC_RULES = dict(termination="cic")


def test_syn_flood_one_flow_per_source_port(tmp_path):
    pk = http_session(0.0, A, B) + syn_flood(20, t0=1.0, attacker=C, victim=B)
    path = write(tmp_path / "f.pcap", sorted(pk, key=lambda p: p.time))
    df = extract_flows([path], FlowConfig(**WHOLE)).frame
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


def test_timeouts_defaults_and_cap(tmp_path):
    pk = [udp(t, A, B, 1000, 2000) for t in (0, 1, 2, 200, 201, 2000, 2001)]
    path = write(tmp_path / "t.pcap", pk)
    assert extract_flows([path], FlowConfig(**WHOLE)).frame.packets.tolist() == [7]
    # default: idle 15 s (NetFlow's inactive timeout), active 120 s (CICFlowMeter's flow timeout)
    assert extract_flows([path]).frame.packets.tolist() == [3, 2, 2]
    idle = extract_flows([path], FlowConfig(idle_timeout_s=120, active_timeout_s=0)).frame
    assert idle.packets.tolist() == [3, 2, 2]
    act = extract_flows([path], FlowConfig(idle_timeout_s=0, active_timeout_s=1.5)).frame
    assert act.packets.tolist() == [2, 1, 2, 2]
    gap = [udp(t, A, B, 1, 2) for t in (0, 14.9, 29.8, 44.6, 100)]  # gaps < 15 s never end it
    assert extract_flows([write(tmp_path / "g.pcap", gap)]).frame.packets.tolist() == [4, 1]
    cap = extract_flows([path], FlowConfig(max_packets=4, **WHOLE)).frame
    assert cap.packets.tolist() == [4] and cap.duration_s.iloc[0] == pytest.approx(200)
    long = [udp(t, A, B, 1, 2) for t in np.arange(0, 300, 10.0)]  # 10 s apart for 300 s
    assert extract_flows([write(tmp_path / "l.pcap", long)],
                         FlowConfig(**CIC_RULES)).frame.packets.tolist() == [13, 13, 4]


def test_direction_initiator_and_synack_first(tmp_path):
    pk = http_session(0.0, A, B)[1:]  # the SYN was not captured: first packet is the SYN-ACK
    df = extract_flows([write(tmp_path / "s.pcap", pk)], FlowConfig(**WHOLE)).frame
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
    cfg = FlowConfig(**WHOLE)
    ex = extract_flows([w1, w2], cfg)
    assert len(ex.frame) == 1
    r = ex.frame.iloc[0]
    assert r.packets == len(s) and r.capture_point == "s-b"  # most packets wins over the name
    tie = extract_flows([write(tmp_path / "s-z.pcap", p1), write(tmp_path / "s-c.pcap", p1)], cfg).frame.iloc[0]
    assert tie.capture_point == "s-c" and tie.packets == len(s)  # ties: alphabetically first
    both = extract_flows([w1, w2], FlowConfig(dedup=False, **WHOLE)).frame.iloc[0]
    assert both.packets == 2 * len(s) - 1


def test_vantage_point_keeps_transmissions_that_missed_it(tmp_path):
    # The blackhole + replay case: the victim A's originals die at its own switch (s-a: 6 packets,
    # the most), its replayer's copies (TTL 59) leave from another switch (s-r) and reach B's (s-b).
    orig = [udp(0.1 * i, A, B, 4000, 5600) for i in range(6)]
    copies = [udp(0.25 + 0.2 * i, A, B, 4000, 5600) for i in range(2)]
    for k, c in enumerate(copies):
        c[IP].ttl, c[IP].id = 59, 100 + k
    at_r = [c.copy() for c in copies]
    at_b = [c.copy() for c in copies]
    for c in at_b:
        c.time += 0.003
    paths = [write(tmp_path / "s-a.pcap", orig), write(tmp_path / "s-b.pcap", at_b), write(tmp_path / "s-r.pcap", at_r)]
    packets = read_packets(paths, points=["s-a", "s-b", "s-r"])
    cfg = FlowConfig(**WHOLE)
    assert flows_of(packets, cfg).frame.packets.tolist() == [6]  # one point alone: the copies are lost
    # one id per transmission (what the follower gives): originals 0..5, each copy one id at s-r and s-b
    tid = np.where(packets["ttl"] == 59, 6 + packets["ip_id"].astype(np.int64) - 100, np.arange(len(packets)))
    fr = flows_of(packets, cfg, transmissions=tid)
    assert fr.frame.packets.tolist() == [8]  # every transmission once
    kept = fr.flows.order
    assert sorted(packets.points[i]
                  for i in packets["point"][kept]) == ["s-a"] * 6 + ["s-b"] * 2  # copies at their last point
    with pytest.raises(ValueError, match="one id per packet"):
        flows_of(packets, cfg, transmissions=tid[:-1])


@pytest.mark.slow  # 4 s on 2 cores
def test_ipv6_flow(tmp_path):
    df = extract_flows([write(tmp_path / "v6.pcap", ipv6_session())]).frame
    assert len(df) == 1 and df.src_ip[0] == "2001:db8::1" and df.protocol[0] == 6
    assert df["Fwd Header Length"][0] == 3 * 20 and df["Bwd Header Length"][0] == 20  # L4 headers (cic)


def test_flow_ids_follow_the_first_packet(tmp_path):
    # keys sort B < C, but C's flow starts first; the RST flow sits between them in time
    pk = sorted(http_session(0.05, A, B, 40001) + http_session(0.0, A, C, 40002) + [tcp(0.07, A, B, 7, 7, "R")],
                key=lambda p: p.time)  # fmt: skip
    df = extract_flows([write(tmp_path / "m.pcap", pk)]).frame
    assert df.packets.sum() == len(pk)
    assert df.flow_id.tolist() == list(range(len(df)))
    assert (np.diff(df.first_ts_ns.to_numpy()) >= 0).all()
    assert df.dst_ip.tolist()[:3] == [C, B, B] and df.dst_port.tolist()[2] == 7


def _mixed_capture(tmp_path, n_sessions=60, seed=3):
    """HTTP sessions (FIN tails), reused client ports, SYN floods with reuse, UDP with idle gaps."""
    rng = np.random.default_rng(seed)
    pk = []
    for k in range(n_sessions):
        pk += http_session(float(rng.uniform(0, 60)), A, B, 41000 + k % 25, n_data=int(rng.integers(1, 6)))
    for burst in (5.0, 25.0, 45.0):  # three bursts reusing the same 30 source ports
        pk += [tcp(burst + 0.002 * i, C, B, 3000 + i % 30, 80, "S", seq=int(rng.integers(1, 2**31)))
               for i in range(60)]  # fmt: skip
    pk += [udp(float(t), A, C, 5000, 53) for t in np.sort(rng.uniform(0, 80, 80))]
    return write(tmp_path / "mixed.pcap", sorted(pk, key=lambda p: p.time))


@pytest.mark.slow  # 7 s on 2 cores
@pytest.mark.parametrize("termination", ["connection", "cic", "timeout"])
@pytest.mark.parametrize("chunk", [300, 2000, 1 << 20])
def test_streaming_gives_the_same_flows(tmp_path, chunk, termination):
    path = _mixed_capture(tmp_path)
    cfg = FlowConfig(termination=termination, idle_timeout_s=15 if termination == "timeout" else None)
    whole = extract_flows([path], cfg).frame
    rep = StreamReport()
    parts = list(iter_flow_frames([path], cfg, chunk_bytes=chunk, report=rep))
    streamed = pd.concat(parts, ignore_index=True)
    if chunk < 1 << 20:
        assert len(parts) > 1  # the capture really was read in several blocks
    every = extract_flows([path], FlowConfig(**WHOLE)).frame.packets.sum()  # cic leaves some packets out
    assert rep.packets == every and rep.flows == len(whole)
    flat = [c for c in whole.columns if not c.startswith("seq_")]
    pd.testing.assert_frame_equal(whole[flat], streamed[flat], check_dtype=False)
    for c in ("seq_time_s", "seq_size", "seq_flags", "seq_dir"):
        assert whole[c].tolist() == streamed[c].tolist(), c


@pytest.mark.parametrize("standard", ["cic", "paper"])
@pytest.mark.parametrize("sequences", [True, False])
def test_the_empty_flow_frame_has_the_columns_and_dtypes_of_a_stream(tmp_path, standard, sequences):
    from uavcas.flows import empty_flow_frame

    pcap = write(tmp_path / "a.pcap", http_session())
    (df,) = iter_flow_frames([pcap], FlowConfig(), standard=standard, sequences=sequences)
    empty = empty_flow_frame(standard, sequences=sequences)
    assert len(empty) == 0 and len(df) > 0
    assert list(empty.columns) == list(df.columns)
    assert {c: str(t) for c, t in empty.dtypes.items() if c != "flow_id"} == \
           {c: str(t) for c, t in df.dtypes.items() if c != "flow_id"}
