"""The two feature standards against values computed by hand from small captures."""

from __future__ import annotations

import shutil
import subprocess

import numpy as np
import pytest
from scapy.layers.inet import IP, UDP, fragment
from scapy.layers.l2 import Ether
from scapy.packet import Raw

from helpers.pcapgen import T0, A, B, C, http_session, tcp, udp, write
from uavcas.flows import FlowConfig, extract_flows
from uavcas.flows.standards.cic import FEATURES
from uavcas.flows.standards.paper import PAPER_FEATURES

US = 1e6
CIC_RULES = FlowConfig(termination="cic")  # CICFlowMeter's segmentation exactly


def _sstd(x):
    return float(np.std(x, ddof=1)) if len(x) > 1 else 0.0


def test_cic_http_session_by_hand(tmp_path):
    df = extract_flows([write(tmp_path / "h.pcap", http_session(0.0, A, B))], CIC_RULES).frame
    assert list(df.columns[-47:]) == list(FEATURES) and df.attrs["feature_standard"] == "cic"
    r = df.iloc[0]  # the server's FIN (packet 9) ends it: 9 packets
    t = np.array([0, 10, 20, 30, 50, 60, 70, 100, 110]) * 1000.0  # us
    pl = np.array([0, 0, 0, 18, 1000, 1000, 1000, 0, 0.0])  # TCP payload bytes
    fwd = np.array([1, 0, 1, 1, 0, 0, 0, 1, 0], dtype=bool)
    lens = np.append(pl, pl[0])  # BasicFlow.firstPacket adds the first payload twice
    iat, fiat, biat = np.diff(t), np.diff(t[fwd]), np.diff(t[~fwd])
    expect = {
        "Flow Duration": 110_000, "Flow Bytes/s": 3018 / 0.11, "Flow Packets/s": 9 / 0.11,
        "Flow IAT Mean": iat.mean(), "Flow IAT Std": _sstd(iat), "Flow IAT Max": 30_000, "Flow IAT Min": 10_000,
        "Min Packet Length": 0, "Max Packet Length": 1000, "Packet Length Mean": lens.mean(),
        "Packet Length Std": _sstd(lens), "Packet Length Variance": np.var(lens, ddof=1),
        "FIN Flag Count": 1, "SYN Flag Count": 2, "RST Flag Count": 0, "PSH Flag Count": 1, "ACK Flag Count": 8,
        "URG Flag Count": 0, "CWE Flag Count": 0, "ECE Flag Count": 0,
        "Down/Up Ratio": 1,  # 5 // 4: integer division
        "Average Packet Size": lens.sum() / 9, "Active Mean": 0, "Idle Mean": 0, "Idle Max": 0,
        "Total Fwd Packets": 4, "Total Backward Packets": 5, "Total Length of Fwd Packets": 18,
        "Total Length of Bwd Packets": 3000, "Fwd Packet Length Max": 18, "Fwd Packet Length Min": 0,
        "Fwd Packet Length Mean": 4.5, "Fwd Packet Length Std": _sstd(pl[fwd]), "Bwd Packet Length Max": 1000,
        "Bwd Packet Length Min": 0, "Bwd Packet Length Mean": 600, "Bwd Packet Length Std": _sstd(pl[~fwd]),
        "Fwd IAT Total": fiat.sum(), "Fwd IAT Mean": fiat.mean(), "Fwd IAT Std": _sstd(fiat), "Fwd IAT Max": 70_000,
        "Bwd IAT Total": biat.sum(), "Bwd IAT Mean": biat.mean(), "Bwd IAT Std": _sstd(biat), "Bwd IAT Max": 40_000,
        "Fwd Header Length": 4 * 20, "Bwd Header Length": 5 * 20,
    }  # fmt: skip
    assert set(expect) == set(FEATURES)
    for k, v in expect.items():
        assert r[k] == pytest.approx(v, rel=1e-12, abs=1e-9), k
    # the trailing flow (client FIN+ACK, server ACK) is CICFlowMeter's too
    tail = df.iloc[1]
    assert (tail.packets, tail["Flow Duration"], tail["Total Fwd Packets"]) == (2, 10_000, 1)


def test_cic_active_idle_single_packet_and_flags(tmp_path):
    pk = [udp(t, A, B, 1000, 2000, size=10) for t in (0, 1, 2, 8, 9, 20, 21)] + [udp(30, B, C, 9, 9, size=0)]
    pk += [tcp(40, A, C, 5, 6, "SE"), tcp(40.5, C, A, 6, 5, "AC")]  # ECE 0x40 / CWR 0x80 flags
    # min_packets=1: CICFlowMeter writes no one-packet flow, but the other policies do, with these features
    df = extract_flows([write(tmp_path / "i.pcap", pk)],
                       FlowConfig(termination="cic", min_packets=1)).frame.set_index("src_port")
    assert 9 not in extract_flows([write(tmp_path / "i2.pcap", pk)], CIC_RULES).frame.src_port.tolist()
    r = df.loc[1000]
    # idle gaps > 5 s: 6 s and 11 s; the active stretches before them: 0->2 s and 8->9 s; the last
    # stretch (20->21 s) is never recorded (no endActiveIdleTime)
    assert r["Idle Mean"] == 8.5 * US and r["Idle Max"] == 11 * US and r["Active Mean"] == 1.5 * US
    assert r["Flow Duration"] == 21 * US and r["Total Length of Fwd Packets"] == 70 and r["Fwd Header Length"] == 56
    single = df.loc[9]  # CICFlowMeter divides by the duration unguarded and has no IAT of one packet
    assert np.isnan(single["Flow Bytes/s"]) and np.isinf(single["Flow Packets/s"]) and np.isnan(single["Flow IAT Mean"])
    assert single["Fwd IAT Total"] == 0 and single["Down/Up Ratio"] == 0 and single["Packet Length Mean"] == 0
    t = df.loc[5]
    assert (t["ECE Flag Count"], t["CWE Flag Count"], t["SYN Flag Count"]) == (1, 1, 1)
    ev = extract_flows([write(tmp_path / "e.pcap", [udp(t, A, B, 1, 2) for t in (0, 10, 20)])], CIC_RULES).frame.iloc[0]
    assert ev["Active Mean"] == 0 and ev["Idle Mean"] == 10 * US  # zero-length active periods are not recorded


def test_paper_standard_by_hand(tmp_path):
    a, b = "10.0.0.10", "10.0.0.2"  # as strings '10.0.0.10' < '10.0.0.2': the authors' direction 0 is a
    pk = [udp(0.0, b, a, 7, 8, size=100), udp(0.1, a, b, 8, 7, size=200), udp(0.3, b, a, 7, 8, size=100),
          udp(0.6, b, a, 7, 8, size=50)]  # fmt: skip
    pk += [tcp(1.0, A, C, 5, 6, "SE"), tcp(1.5, C, A, 6, 5, "AC")]
    df = extract_flows([write(tmp_path / "p.pcap", pk)], FlowConfig(view="hostpair", min_packets=1),
                       standard="paper").frame
    assert list(df.columns[-47:]) == list(PAPER_FEATURES) and df.attrs["feature_standard"] == "paper"
    r = df.set_index("src_ip").loc[b]
    t = np.array([T0 + x for x in (0.0, 0.1, 0.3, 0.6)])  # float epoch seconds, as tshark's
    size = np.array([142, 242, 142, 92])  # frame bytes: 14 + 20 + 8 + payload
    d0 = np.array([0, 1, 0, 0], dtype=bool)  # sent by a, the string-smaller address
    dur, iat = t[-1] - t[0], np.diff(t)
    expect = {
        "Flow Duration": dur, "Total Packets": 4, "Total Length of Packets": 618, "Flow Bytes/s": 618 / dur,
        "Flow Packets/s": 4 / dur, "Flow IAT Total": iat.sum(), "Flow IAT Mean": iat.mean(),
        "Flow IAT Std": iat.std(), "Flow IAT Max": iat.max(), "Flow IAT Min": iat.min(),
        "Min Packet Length": 92, "Max Packet Length": 242, "Packet Length Mean": size.mean(),
        "Packet Length Std": size.std(), "Packet Length Variance": size.var(),  # population (ddof 0)
        **{f: 0 for f in ("FIN Flag Count", "SYN Flag Count", "RST Flag Count", "PSH Flag Count", "ACK Flag Count",
                          "URG Flag Count", "CWE Flag Count", "ECE Flag Count")},
        "Header Length": 80, "Average Packet Size": 618 / 4,
        "Total Fwd Packets": 1, "Total Bwd Packets": 3, "Total Length of Fwd Packets": 242,
        "Total Length of Bwd Packets": 376, "Fwd Packets/s": 1 / dur, "Bwd Packets/s": 3 / dur,
        "Fwd Packet Length Max": 242, "Fwd Packet Length Min": 242, "Fwd Packet Length Mean": 242,
        "Fwd Packet Length Std": 0, "Bwd Packet Length Max": 142, "Bwd Packet Length Min": 92,
        "Bwd Packet Length Mean": size[~d0].mean(), "Bwd Packet Length Std": size[~d0].std(),
        "Fwd IAT Total": 0, "Fwd IAT Mean": 0, "Fwd IAT Std": 0, "Bwd IAT Total": t[3] - t[0],
        "Bwd IAT Mean": np.diff(t[~d0]).mean(), "Bwd IAT Std": np.diff(t[~d0]).std(),
        "Fwd Header Length": 20, "Bwd Header Length": 60,
    }  # fmt: skip
    assert set(expect) == set(PAPER_FEATURES)
    for k, v in expect.items():
        assert r[k] == pytest.approx(v, rel=1e-12, abs=1e-12), k
    # their code counts the ECE bit (0x40) as "CWE Flag Count" and CWR (0x80) as "ECE Flag Count"
    s = df.set_index("src_ip").loc[A]
    assert (s["CWE Flag Count"], s["ECE Flag Count"], s["Header Length"]) == (1, 1, 40)
    one = extract_flows([write(tmp_path / "o.pcap", [udp(0, A, B, 1, 2)])], standard="paper").frame.iloc[0]
    assert np.isnan(one[list(PAPER_FEATURES)].to_numpy(float)).all()  # their generator writes no row


def _udp_datagram(t, src, dst, sport, dport, payload, ip_id):
    p = IP(src=src, dst=dst, id=ip_id) / UDP(sport=sport, dport=dport) / Raw(payload)
    frags = [Ether() / f for f in fragment(p, fragsize=400)]
    for k, f in enumerate(frags):
        f.time = T0 + t + 0.0001 * k
    return frags


def test_cic_lengths_sum_to_the_captures_tcp_udp_payload(tmp_path):
    payloads = []
    pk = http_session(0.0, A, B) + http_session(0.2, C, B, 40100, n_data=5)
    payloads += [18, 3000, 18, 5000]
    pk += [udp(0.5 + 0.01 * k, A, C, 5000, 53, size=40 + k) for k in range(5)]
    payloads += [40 + k for k in range(5)]
    frags = _udp_datagram(0.7, A, C, 6000, 7000, b"z" * 1500, ip_id=77)
    pk += [frags[1], frags[0], *frags[2:]]  # the second fragment first: reordered on the wire
    payloads.append(1500)
    pk.append(tcp(0.9, A, B, 9, 9, "R"))
    path = write(tmp_path / "sum.pcap", sorted(pk, key=lambda p: p.time))
    df = extract_flows([path]).frame
    total = (df["Total Length of Fwd Packets"] + df["Total Length of Bwd Packets"]).sum()
    assert total == sum(payloads)
    frag_flow = df[(df.src_port == 6000)]
    assert len(frag_flow) == 1 and frag_flow.packets.iloc[0] == len(frags)  # the datagram in ONE flow
    if shutil.which("tshark"):
        out = subprocess.run(["tshark", "-n", "-r", str(path), "-T", "fields", "-e", "tcp.len", "-e", "udp.length"],
                             capture_output=True, text=True, check=True).stdout  # fmt: skip
        tsh = 0
        for line in out.splitlines():
            tl, ul = (line.split("\t") + [""])[:2]
            tsh += int(tl) if tl else (int(ul.split(",")[0]) - 8 if ul else 0)
        assert total == tsh
