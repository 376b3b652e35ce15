"""Packet table: containers, link types, IPv4/IPv6, TCP/UDP/ICMP fields, truncation handling."""

from __future__ import annotations

import struct

import numpy as np
import pytest
from scapy.layers.inet import IP, TCP
from scapy.layers.inet6 import IPv6
from scapy.layers.l2 import (
    CookedLinuxV2,  # noqa: E402
    Ether,
)
from scapy.packet import Raw

from helpers.pcapgen import T0, A, B, http_session, icmp, ipv6_session, sll, tcp, udp, vlan_tcp, write, write_pcapng
from uavcas.flows import CaptureError, read_packets


def test_ethernet_ipv4_fields(tmp_path):
    pk = [tcp(0.5, A, B, 1234, 80, "PA", b"abc", seq=77, ttl=33, ip_id=4242), udp(1.0, B, A, 53, 999, size=10),
          icmp(2.0, A, B)]
    t = read_packets([write(tmp_path / "x.pcap", pk)]).to_pandas()
    assert list(t.src_ip) == [A, B, A] and list(t.dst_ip) == [B, A, B]
    assert list(t.proto) == [6, 17, 1]
    assert list(t.sport) == [1234, 53, 0] and list(t.dport) == [80, 999, 0]
    assert t.tcp_flags[0] == 0x18 and t.tcp_seq[0] == 77 and t.ttl[0] == 33 and t.ip_id[0] == 4242
    assert list(t.frame_len) == [len(p) for p in pk]
    assert list(t.ip_hdr_len) == [20, 20, 20] and list(t.l4_hdr_len) == [20, 8, 8]
    assert t.ts_s[0] == pytest.approx(T0 + 0.5, abs=1e-6)


def test_pcapng_same_as_pcap(tmp_path):
    pk = http_session()
    a = read_packets([write(tmp_path / "a.pcap", pk)]).to_pandas()
    b = read_packets([write_pcapng(tmp_path / "b.pcapng", pk)]).to_pandas()
    for col in ("src_ip", "dst_ip", "sport", "dport", "frame_len", "tcp_flags"):
        assert list(a[col]) == list(b[col])
    np.testing.assert_allclose(a.ts_s, b.ts_s, atol=1e-6)


def test_sll_sll2_vlan_raw(tmp_path):
    s = read_packets([write(tmp_path / "sll.pcap", [sll(0, A, B, 1, 2, "S"), sll(0.1, B, A, 2, 1, "SA")])]).to_pandas()
    assert list(s.src_ip) == [A, B] and list(s.tcp_flags) == [2, 0x12]
    p2 = CookedLinuxV2(proto=0x0800, lladdrtype=1, lladdrlen=6) / IP(src=A, dst=B) / TCP(sport=7, dport=8, flags="S")
    p2.time = T0
    s2 = read_packets([write(tmp_path / "sll2.pcap", [p2], linktype=276)]).to_pandas()
    assert list(s2.sport) == [7] and list(s2.frame_len) == [len(p2)]
    v = read_packets([write(tmp_path / "vlan.pcap", [vlan_tcp(0, A, B, 5, 6, "S")])]).to_pandas()
    assert list(v.sport) == [5] and list(v.src_ip) == [A]
    raw = IP(src=A, dst=B) / TCP(sport=9, dport=10) / Raw(b"zz")
    raw.time = T0
    r = read_packets([write(tmp_path / "raw.pcap", [raw], linktype=101)]).to_pandas()
    assert list(r.dport) == [10] and list(r.frame_len) == [len(raw)]


@pytest.mark.slow  # 4 s on 2 cores
def test_ipv6_hop_limit_and_ports(tmp_path):
    t = read_packets([write(tmp_path / "v6.pcap", ipv6_session())]).to_pandas()
    assert set(t.ip_version) == {6}
    assert t.src_ip[0] == "2001:db8::1" and t.dst_ip[0] == "2001:db8::2"
    assert list(t.sport) == [5555, 443, 5555, 5555] and t.ttl[0] == 60
    assert list(t.ip_hdr_len) == [40] * 4


def test_truncated_file_names_file_and_offset(tmp_path):
    path = write(tmp_path / "t.pcap", http_session())
    data = path.read_bytes()
    cut = tmp_path / "cut.pcap"
    cut.write_bytes(data[:-30])
    with pytest.raises(CaptureError) as e:
        read_packets([cut])
    msg = str(e.value)
    assert str(cut) in msg and "byte offset" in msg and "truncated" in msg
    # the offset is the start of the last record
    off = int(msg.split("byte offset ")[1].split()[0])
    assert struct.unpack_from("<I", data, off + 8)[0] > 30
    table = read_packets([cut], allow_truncated=True)
    assert len(table) == len(http_session()) - 1
    assert table.truncations and table.truncations[0].offset == off


def test_corrupt_and_unknown(tmp_path):
    bad = tmp_path / "bad.pcap"
    bad.write_bytes(b"NOTAPCAPFILE" * 3)
    with pytest.raises(CaptureError, match="byte offset 0"):
        read_packets([bad])
    path = write(tmp_path / "ok.pcap", http_session())
    data = bytearray(path.read_bytes())
    struct.pack_into("<I", data, 24 + 8, 0x7FFFFFFF)  # absurd captured length of record 0
    (tmp_path / "corrupt.pcap").write_bytes(bytes(data))
    with pytest.raises(CaptureError, match="corrupt record header.*|byte offset 24"):
        read_packets([tmp_path / "corrupt.pcap"])
    ng = write_pcapng(tmp_path / "ok.pcapng", http_session())
    (tmp_path / "cut.pcapng").write_bytes(ng.read_bytes()[:-10])
    with pytest.raises(CaptureError, match="pcapng block"):
        read_packets([tmp_path / "cut.pcapng"])
    assert len(read_packets([tmp_path / "cut.pcapng"], allow_truncated=True)) == len(http_session()) - 1


def _snap(path, out, snaplen):
    """Rewrite a little-endian pcap as captured with `snaplen` (header field and every record)."""
    data = path.read_bytes()
    buf = bytearray(data[:16]) + struct.pack("<I", snaplen) + data[20:24]
    off = 24
    while off < len(data):
        s, f, incl, orig = struct.unpack_from("<IIII", data, off)
        keep = min(incl, snaplen)
        buf += struct.pack("<IIII", s, f, keep, orig) + data[off + 16 : off + 16 + keep]
        off += 16 + incl
    out.write_bytes(bytes(buf))
    return out


def test_short_snaplen_is_counted_not_guessed(tmp_path):
    sessions = [p for k in range(4) for p in http_session(0.2 * k, A, B, 40000 + k)]
    full = write(tmp_path / "full.pcap", sessions)
    # snap length 40 = Ethernet + IP + 6 bytes of TCP: ports readable, flags not -> left out, counted
    t40 = read_packets([_snap(full, tmp_path / "s40.pcap", 40)])
    assert len(t40) == 0 and t40.stats[0].l4_cut == len(sessions) and t40.stats[0].snaplen == 40
    assert any("transport header cut" in w and "snap length 40" in w for w in t40.stats[0].warnings())
    # snap length 30: not even the IP header
    t30 = read_packets([_snap(full, tmp_path / "s30.pcap", 30)])
    assert len(t30) == 0 and t30.stats[0].dropped_short == len(sessions)
    assert any("IP header cut" in w for w in t30.stats[0].warnings())
    # snap length 54 (Ethernet + IP + 20 bytes of TCP): every field, the payload length from the IP header
    t54 = read_packets([_snap(full, tmp_path / "s54.pcap", 54)]).to_pandas()
    ref = read_packets([full]).to_pandas()
    for col in ("sport", "dport", "tcp_flags", "ip_len", "frame_len"):
        assert t54[col].tolist() == ref[col].tolist(), col
    assert set(t54.cap_len) == {54}


def test_ipv6_tcp_at_snaplen_68_keeps_ports_and_flags(tmp_path):
    full = write(tmp_path / "v6.pcap", ipv6_session())
    t = read_packets([_snap(full, tmp_path / "v6s.pcap", 68)]).to_pandas()  # 14 bytes of TCP
    assert list(t.sport) == [5555, 443, 5555, 5555] and list(t.tcp_flags) == [0x02, 0x12, 0x10, 0x18]
    assert read_packets([tmp_path / "v6s.pcap"]).stats[0].l4_cut == 0


@pytest.mark.parametrize(
    "family",
    [struct.pack("<I", 2), struct.pack(">I", 2), bytes.fromhex("0f000800"), struct.pack("<I", 0x0800),
     struct.pack("<I", 24), struct.pack(">I", 30), struct.pack("<I", 10), bytes.fromhex("000086dd")],
)  # fmt: skip
def test_dlt_null_family_field_in_any_byte_order(tmp_path, family):
    v6 = family in (struct.pack("<I", 24), struct.pack(">I", 30), struct.pack("<I", 10), bytes.fromhex("000086dd"))
    ip = IPv6(src="2001:db8::1", dst="2001:db8::2") if v6 else IP(src=A, dst=B)
    body = bytes(ip / TCP(sport=1234, dport=80, flags="S"))
    path = tmp_path / "null.pcap"
    rec = family + body
    path.write_bytes(struct.pack("<IHHiIII", 0xA1B2C3D4, 2, 4, 0, 0, 65535, 0)
                     + struct.pack("<IIII", int(T0), 0, len(rec), len(rec)) + rec)  # fmt: skip
    t = read_packets([path])
    assert len(t) == 1 and int(t["sport"][0]) == 1234 and int(t["ip_version"][0]) == (6 if v6 else 4)
    bad = tmp_path / "bad.pcap"
    rec = struct.pack("<I", 99) + body
    bad.write_bytes(path.read_bytes()[:24] + struct.pack("<IIII", int(T0), 0, len(rec), len(rec)) + rec)
    tb = read_packets([bad])
    assert len(tb) == 0 and tb.stats[0].null_unknown == 1 and tb.stats[0].warnings()


def test_fragments_join_their_datagram_and_orphans_are_counted(tmp_path):
    from scapy.layers.inet import UDP, fragment

    def datagram(t, ip_id, sport):
        d = IP(src=A, dst=B, id=ip_id) / UDP(sport=sport, dport=53) / Raw(b"q" * 1400)
        out = [Ether() / f for f in fragment(d, fragsize=500)]
        for k, f in enumerate(out):
            f.time = T0 + t + 0.001 * k
        return out

    d1, d2, d3 = datagram(0.0, 11, 4001), datagram(1.0, 12, 4001), datagram(2.0, 13, 4002)
    pk = [d1[2], d1[0], d1[1]] + d2 + d3[1:]  # d1 reordered, d3 lost its first fragment
    pk += [udp(3.0, A, B, 4001, 53)]
    path = write(tmp_path / "frag.pcap", pk)
    t = read_packets([path])
    assert t.stats[0].orphan_fragments == len(d3) - 1 and any("first fragment" in w for w in t.stats[0].warnings())
    df = t.to_pandas()
    assert len(df) == len(pk) - (len(d3) - 1) and (df.sport == 4001).all() and (df.dport == 53).all()
    from uavcas.flows import extract_flows

    fr = extract_flows([path]).frame
    assert fr.packets.tolist() == [len(d1) + len(d2) + 1] and fr.src_port.tolist() == [4001]
    # across blocks: the same answer when the file is read a few records at a time
    small = read_packets([path], chunk_bytes=700)
    assert small.stats[0].orphan_fragments == len(d3) - 1
    assert sorted(small["ts_ns"].tolist()) == sorted(t["ts_ns"].tolist())


def test_timestamps_are_exact_integer_nanoseconds(tmp_path):
    from decimal import Decimal

    from scapy.utils import wrpcap

    p = tcp(0, A, B, 1, 2, "S")
    p.time = Decimal(int(T0)) + Decimal("0.123456789")  # a float would already have lost the ns
    wrpcap(str(tmp_path / "ns.pcap"), [p], nano=True)
    t = read_packets([tmp_path / "ns.pcap"])
    assert int(t["ts_ns"][0]) == int(T0) * 10**9 + 123456789
    assert t["ts_ns"].dtype == np.int64


@pytest.mark.shared
def test_real_pcapng_and_pcap(shared_data):
    d = shared_data / "pcaps" / "lwerdna-filesamples"
    ng = read_packets([d / "200722_tcp_anon.pcapng"])
    pc = read_packets([d / "simple_http.pcap"])
    assert len(ng) > 0 and len(pc) > 0
    assert set(np.unique(pc["proto"])) <= {1, 6, 17}


def test_nanosecond_big_endian_and_empty(tmp_path):
    pk = http_session()
    from scapy.utils import wrpcap

    wrpcap(str(tmp_path / "ns.pcap"), pk, nano=True)
    a = read_packets([tmp_path / "ns.pcap"]).to_pandas()
    np.testing.assert_allclose(a.ts_s, [float(p.time) for p in pk], atol=1e-6)
    # big-endian pcap: swap every header word of a little-endian file
    data = bytearray(write(tmp_path / "le.pcap", pk).read_bytes())
    out = bytearray(struct.pack(">IHHiIII", 0xA1B2C3D4, 2, 4, 0, 0, 65535, 1))
    off = 24
    while off < len(data):
        s, f, incl, orig = struct.unpack_from("<IIII", data, off)
        out += struct.pack(">IIII", s, f, incl, orig) + data[off + 16 : off + 16 + incl]
        off += 16 + incl
    (tmp_path / "be.pcap").write_bytes(bytes(out))
    b = read_packets([tmp_path / "be.pcap"]).to_pandas()
    assert b.sport.tolist() == a.sport.tolist() and b.frame_len.tolist() == a.frame_len.tolist()
    empty = write(tmp_path / "empty.pcap", [])
    from uavcas.flows import extract_flows

    ex = extract_flows([empty])
    assert len(ex.packets) == 0 and len(ex.frame) == 0 and "Flow Duration" in ex.frame.columns


def test_icmp_errors_carry_the_quoted_packet(tmp_path):
    """A host-unreachable quoting a TCP SYN, a port-unreachable quoting a UDP datagram (each as a
    router or host builds it: IP header + the offending packet), an ICMPv6 unreachable quoting a
    SYN, an echo request (no error) and an error cut by the snap length: only the quotes
    captured whole fill the q_* columns."""
    from scapy.layers.inet import ICMP, UDP
    from scapy.layers.inet6 import ICMPv6DestUnreach

    syn = IP(src=A, dst=B, ttl=61, id=321) / TCP(sport=40001, dport=80, flags="S", seq=0xDEADBEEF)
    dgram = IP(src=B, dst=A, ttl=7, id=654) / UDP(sport=5353, dport=9999) / Raw(b"q" * 30)
    syn6 = IPv6(src="2001:db8::1", dst="2001:db8::2", hlim=50) / TCP(sport=4444, dport=443, flags="S", seq=99)

    def at(t, p):
        p.time = T0 + t
        return p

    pk = [
        at(0.1, Ether() / IP(src="10.0.0.9", dst=A) / ICMP(type=3, code=1) / bytes(syn)),
        at(0.2, Ether() / IP(src=A, dst=B) / ICMP(type=3, code=3) / bytes(dgram)),
        at(0.3, Ether() / IPv6(src="2001:db8::2", dst="2001:db8::1") / ICMPv6DestUnreach(code=4) / bytes(syn6)),
        icmp(0.4, A, B),
        tcp(0.5, A, B, 1, 2, "A"),
    ]
    t = read_packets([write(tmp_path / "icmp.pcap", pk)]).to_pandas()
    assert list(t.q_proto) == [6, 17, 6, 0, 0]
    assert list(t.q_sport) == [40001, 5353, 4444, 0, 0] and list(t.q_dport) == [80, 9999, 443, 0, 0]
    assert list(t.q_tcp_seq) == [0xDEADBEEF, 0, 99, 0, 0]
    assert list(t.q_ip_id[:2]) == [321, 654] and list(t.q_ttl[:3]) == [61, 7, 50]
    a, b = (0xFFFF00000000 | int.from_bytes(bytes(map(int, ip.split("."))), "big") for ip in (A, B))
    assert list(t.q_src_lo[:2]) == [a, b] and list(t.q_dst_lo[:2]) == [b, a]
    assert t.q_src_lo[2] == 1 and t.q_dst_lo[2] == 2  # 2001:db8::1 -> 2001:db8::2, low 64 bits
    # the same error captured with the quote's transport bytes cut: no quote, nothing guessed
    cut = write(tmp_path / "cut.pcap", pk[:1])
    raw = bytearray(cut.read_bytes())
    snap = 14 + 20 + 8 + 20 + 4  # Ethernet, IP, ICMP, quoted IP header, 4 of the 8 quoted TCP bytes
    struct.pack_into("<I", raw, 16, snap)  # the file header's snap length
    n = struct.unpack_from("<I", raw, 24 + 8)[0]
    struct.pack_into("<I", raw, 24 + 8, snap)  # the record's captured length
    del raw[24 + 16 + snap:24 + 16 + n]
    (tmp_path / "cut.pcap").write_bytes(bytes(raw))
    c = read_packets([tmp_path / "cut.pcap"]).to_pandas()
    assert len(c) == 1 and c.proto[0] == 1 and c.q_proto[0] == 0 and c.q_sport[0] == 0
