"""Packet table: containers, link types, IPv4/IPv6, TCP/UDP/ICMP fields, truncation handling."""

from __future__ import annotations

import struct

import numpy as np
import pytest
from pcapgen import A, B, T0, http_session, icmp, ipv6_session, sll, tcp, udp, vlan_tcp, write, write_pcapng
from scapy.layers.inet import IP, TCP
from scapy.layers.l2 import CookedLinuxV2
from scapy.packet import Raw

from uavcas.flows import CaptureError, read_packets


def test_ethernet_ipv4_fields(tmp_path):
    pk = [tcp(0.5, A, B, 1234, 80, "PA", b"abc", seq=77, ttl=33, ip_id=4242), udp(1.0, B, A, 53, 999, size=10), icmp(2.0, A, B)]
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


def test_snaplen_truncated_packet_keeps_ip_fields(tmp_path):
    p = tcp(0, A, B, 1000, 80, "PA", b"x" * 500)
    path = write(tmp_path / "snap.pcap", [p, tcp(0.1, B, A, 80, 1000, "A")])
    data = bytearray(path.read_bytes())
    # shrink record 0 to 40 captured bytes (Ethernet + IP + 6 bytes of TCP): ports readable, flags not
    struct.pack_into("<I", data, 24 + 8, 40)
    rec1 = data[24 + 16 + len(p) :]
    fixed = bytes(data[: 24 + 16 + 40]) + bytes(rec1)
    (tmp_path / "snap2.pcap").write_bytes(fixed)
    t = read_packets([tmp_path / "snap2.pcap"]).to_pandas()
    assert len(t) == 2 and t.frame_len[0] == len(p) and t.cap_len[0] == 40
    assert t.sport[0] == 0 and t.tcp_flags[0] == 0  # L4 header not captured: no ports rather than garbage
    assert t.sport[1] == 80


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
