"""`--termination cic` against an independent, per-packet re-statement of CICFlowMeter-4.0
(`cicflowmeter_oracle`): the same flows and all 47 features, on real and built captures."""

from __future__ import annotations

import math
from collections import Counter

import numpy as np
import pytest
from cicflowmeter_oracle import cicflowmeter_flows
from scapy.layers.inet import ICMP, IP
from scapy.layers.l2 import Ether

from helpers.pcapgen import T0, A, B, C, http_session, tcp, udp, write
from uavcas.flows import FlowConfig, extract_flows
from uavcas.flows.standards.cic import FEATURES

CIC = FlowConfig(termination="cic")
RTOL, ATOL = 1e-9, 1e-6
NFSTREAM_PCAPS = ("aimini-http.pcap", "ftp.pcap", "http-manipulated.pcap", "http_auth.pcap", "synscan.pcap")


def _key(src_ip, src_port, dst_ip, dst_port, protocol, first_ts_us) -> tuple:
    return (str(src_ip), int(src_port), str(dst_ip), int(dst_port), int(protocol), int(first_ts_us))


def _same(x: float, y: float) -> bool:
    """Equal within RTOL/ATOL; NaN == NaN and inf == inf (CICFlowMeter's unguarded divisions)."""
    if math.isnan(x) or math.isnan(y):
        return math.isnan(x) and math.isnan(y)
    if math.isinf(x) or math.isinf(y):
        return x == y
    return bool(np.isclose(x, y, rtol=RTOL, atol=ATOL))


def compare(pcap) -> tuple[int, int]:
    """Assert that uavcas's cic flows of `pcap` are CICFlowMeter's; returns (flows, values) compared.

    Compared: TCP and UDP flows only. CICFlowMeter gives every other IPv4 packet protocol 0 and
    no ports (ICMP and the rest merge per address pair) where uavcas keeps the protocol
    (`uavcas.flows.standards.cic`, "Deliberate differences"), and it cannot see the transport header of later
    IP fragments where uavcas reassigns them: keys with fragments are left out as well (none of
    the captures here has any). Direction: CICFlowMeter compares source addresses, uavcas
    endpoints (`uavcas.flows.termination`, "Known difference"); both are the same unless the two
    addresses are equal, so such flows (a host talking to itself, all of simple_http.pcap) are
    compared with the oracle's `direction_by_port` rule, the others with the literal one.
    """
    literal = cicflowmeter_flows(pcap)
    by_port = cicflowmeter_flows(pcap, direction_by_port=True)
    oracle = [f for f in literal if f.src_ip != f.dst_ip] + [f for f in by_port if f.src_ip == f.dst_ip]
    oracle = [f for f in oracle if f.protocol in (6, 17)]
    fragmented = {(f.src_ip, f.src_port, f.dst_ip, f.dst_port, f.protocol) for f in oracle if f.fragmented}
    oracle = [f for f in oracle if (f.src_ip, f.src_port, f.dst_ip, f.dst_port, f.protocol) not in fragmented]
    theirs = {_key(f.src_ip, f.src_port, f.dst_ip, f.dst_port, f.protocol, f.first_ts_us): f for f in oracle}
    assert len(theirs) == len(oracle)  # the key is unique: a multiset comparison is a set one

    df = extract_flows([pcap], CIC, sequences=False).frame
    df = df[df.protocol.isin([6, 17])]
    ours = {}
    for row in df.to_dict("records"):
        k = _key(row["src_ip"], row["src_port"], row["dst_ip"], row["dst_port"], row["protocol"],
                 row["first_ts_ns"] // 1000)
        if k[:5] not in fragmented:
            assert k not in ours, k
            ours[k] = row

    assert sorted(ours) == sorted(theirs), (sorted(set(ours) - set(theirs)), sorted(set(theirs) - set(ours)))
    wrong = []
    for k, f in theirs.items():
        row = ours[k]
        if row["packets"] != f.packets:
            wrong.append((k, "packets", f.packets, row["packets"]))
        for name in FEATURES:
            if not _same(float(f.features[name]), float(row[name])):
                wrong.append((k, name, f.features[name], row[name]))
    assert not wrong, wrong[:20]
    return len(theirs), len(theirs) * len(FEATURES)


@pytest.mark.shared
@pytest.mark.parametrize("name",
                         [f"nfstream-tests/{n}" for n in NFSTREAM_PCAPS] + ["lwerdna-filesamples/simple_http.pcap"])
def test_cic_flows_equal_cicflowmeter_on_real_captures(shared_data, name):
    pcap = shared_data / "pcaps" / name
    if name.startswith("nfstream-tests/"):  # every capture of the folder is listed here
        assert sorted(p.name for p in pcap.parent.glob("*.pcap")) == sorted(NFSTREAM_PCAPS)
    flows, values = compare(pcap)
    assert flows >= 2 and values == flows * 47


def _built_capture() -> list:
    pk = []
    # 1. server-first close: the backward FIN closes the flow at once, the client's FIN/ACK and
    #    the last ACK form a second, "appendix" flow (CICIDS2017's TCP appendices)
    pk += http_session(t0=0.0, sport=40001)
    # 2. client-first close with a retransmitted forward FIN (dropped), then the server's FIN
    #    closes; the client's last ACK is a one-packet flow (not written)
    s = 40002
    pk += [tcp(1.000, A, B, s, 80, "S", seq=100), tcp(1.010, B, A, 80, s, "SA", seq=900, ack=101),
           tcp(1.020, A, B, s, 80, "PA", b"q" * 30, seq=101, ack=901),
           tcp(1.030, B, A, 80, s, "PA", b"r" * 700, seq=901, ack=131),
           tcp(1.040, A, B, s, 80, "FA", seq=131, ack=1601), tcp(1.540, A, B, s, 80, "FA", seq=131, ack=1601),
           tcp(1.545, B, A, 80, s, "A", seq=1601, ack=132), tcp(7.000, B, A, 80, s, "FA", seq=1601, ack=132),
           tcp(7.010, A, B, s, 80, "A", seq=132, ack=1602)]  # fmt: skip
    # 3. RST in both directions: a forward RST, and a backward RST after an idle gap > 5 s
    pk += [tcp(2.000, A, B, 40003, 22, "S"), tcp(2.001, B, A, 22, 40003, "SA"), tcp(2.002, A, B, 40003, 22, "A"),
           tcp(2.500, A, B, 40003, 22, "RA")]  # fmt: skip
    pk += [tcp(3.000, A, B, 40004, 23, "S"), tcp(3.002, B, A, 23, 40004, "SA"),
           tcp(4.500, A, B, 40004, 23, "PA", b"x" * 10), tcp(11.000, B, A, 23, 40004, "R")]  # fmt: skip
    # 4. a SYN-ACK-first flow (its SYN not captured): CICFlowMeter takes the SYN-ACK's sender as
    #    forward; ECE/CWR/URG flags are counted
    pk += [tcp(5.000, B, A, 443, 40005, "SA"), tcp(5.001, A, B, 40005, 443, "AE"),
           tcp(5.300, A, B, 40005, 443, "PAUC", b"h" * 99), tcp(5.310, B, A, 443, 40005, "PA", b"k" * 1400),
           tcp(5.320, B, A, 443, 40005, "PA", b"k" * 17)]  # fmt: skip
    # 5. a UDP flow longer than 120 s with packets both ways around the flow timeout: the packet
    #    121 s after the first (sent by the old flow's destination) starts a flow that keeps the
    #    old orientation and counts that packet forward; a further timeout at 245 s; gaps > 5 s
    #    (idle), between 1 and 5 s (detectUpdateSubflows) and within 1 s
    for t, fwd, size in [(10, True, 40), (10.2, False, 300), (12.5, True, 40), (60, False, 300), (119.9, True, 44),
                         (131.0, False, 310), (131.5, True, 41), (133.0, False, 320), (200.0, True, 41),
                         (251.5, True, 12), (252.0, False, 15), (258.0, False, 16)]:  # fmt: skip
        pk.append(udp(t, A, C, 5353, 5000, size) if fwd else udp(t, C, A, 5000, 5353, size))
    # 6. one-packet flows (never written) and a zero-duration flow: Flow Bytes/s NaN (0 bytes in
    #    0 s), Flow Packets/s inf
    pk += [udp(20.0, B, C, 6000, 53, 20), tcp(21.0, C, B, 40006, 80, "S")]
    pk += [tcp(22.0, C, A, 40007, 25, "S"), tcp(22.0000004, A, C, 25, 40007, "RA")]
    # ICMP (protocol 0 in CICFlowMeter: not compared, must not disturb the rest)
    for t, s_, d_ in [(23.0, A, B), (23.1, B, A)]:
        p = Ether() / IP(src=s_, dst=d_) / ICMP()
        p.time = T0 + t
        pk.append(p)
    return sorted(pk, key=lambda p: p.time)


def test_cic_flows_equal_cicflowmeter_on_a_built_capture(tmp_path):
    pcap = write(tmp_path / "cic_cases.pcap", _built_capture())
    flows, _ = compare(pcap)
    got = extract_flows([pcap], CIC, sequences=False).frame
    # the cases are there: appendix flow (1), the client-first close (2), both RST flows (3), SYN-ACK first (4), three
    # UDP flows cut by the flow timeout (5), the zero-duration flow (6); no one-packet flow is written
    assert flows == 2 + 1 + 2 + 1 + 3 + 1 and (got.packets >= 2).all()
    by_port = Counter(zip(got.src_port, got.dst_port))
    assert by_port[(40001, 80)] == 2 and by_port[(443, 40005)] == 1 and by_port[(5353, 5000)] == 3
    zero = got[got.src_port == 40007].iloc[0]
    assert np.isnan(zero["Flow Bytes/s"]) and np.isinf(zero["Flow Packets/s"])
