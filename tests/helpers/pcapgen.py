"""Small scapy-built captures for the flow tests (each a few dozen packets, written in ms)."""

from __future__ import annotations

from pathlib import Path

from scapy.layers.inet import ICMP, IP, TCP, UDP
from scapy.layers.inet6 import IPv6
from scapy.layers.l2 import CookedLinux, Dot1Q, Ether
from scapy.packet import Raw
from scapy.utils import PcapNgWriter, wrpcap

T0 = 1_600_000_000.0
A, B, C = "10.0.0.1", "10.0.0.2", "10.0.0.3"


def tcp(t, src, dst, sport, dport, flags, payload=b"", seq=1, ack=0, ttl=64, ip_id=0, l2=Ether):
    p = IP(src=src, dst=dst, ttl=ttl, id=ip_id) / TCP(sport=sport, dport=dport, flags=flags, seq=seq, ack=ack)
    if payload:
        p = p / Raw(payload)
    if l2 is not None:
        p = l2() / p
    p.time = T0 + t
    return p


def http_session(t0=0.0, client=A, server=B, sport=40000, n_data=3, l2=Ether):
    """Handshake, GET, n_data x 1000-byte responses with ACKs, FIN/ACK teardown (server first),
    with consistent sequence and acknowledgement numbers (client ISN 1000, server ISN 5000)."""
    get = b"GET / HTTP/1.1\r\n\r\n"
    c, s = 1001, 5001  # next sequence numbers after the SYNs
    pk = [
        tcp(t0, client, server, sport, 80, "S", seq=1000, l2=l2),
        tcp(t0 + 0.010, server, client, 80, sport, "SA", seq=5000, ack=c, l2=l2),
        tcp(t0 + 0.020, client, server, sport, 80, "A", seq=c, ack=s, l2=l2),
        tcp(t0 + 0.030, client, server, sport, 80, "PA", get, seq=c, ack=s, l2=l2),
    ]
    c += len(get)
    for k in range(n_data):
        pk.append(tcp(t0 + 0.050 + 0.010 * k, server, client, 80, sport, "A", b"x" * 1000, seq=s, ack=c, l2=l2))
        s += 1000
    pk.append(tcp(t0 + 0.100, client, server, sport, 80, "A", seq=c, ack=s, l2=l2))
    pk.append(tcp(t0 + 0.110, server, client, 80, sport, "FA", seq=s, ack=c, l2=l2))
    pk.append(tcp(t0 + 0.120, client, server, sport, 80, "FA", seq=c, ack=s + 1, l2=l2))
    pk.append(tcp(t0 + 0.130, server, client, 80, sport, "A", seq=s + 1, ack=c + 1, l2=l2))
    return pk


def syn_flood(n=20, t0=1.0, attacker=C, victim=B, interval_s=0.001):
    return [tcp(t0 + interval_s * i, attacker, victim, 2000 + i, 80, "S", ip_id=i) for i in range(n)]


def udp(t, src, dst, sport, dport, size=100, l2=Ether):
    p = l2() / IP(src=src, dst=dst) / UDP(sport=sport, dport=dport) / Raw(b"u" * size)
    p.time = T0 + t
    return p


def icmp(t, src, dst):
    p = Ether() / IP(src=src, dst=dst) / ICMP()
    p.time = T0 + t
    return p


def ipv6_session(t0=0.0):
    a, b = "2001:db8::1", "2001:db8::2"
    out = []
    for k, (s, d, sp, dp, fl) in enumerate(
        [(a, b, 5555, 443, "S"), (b, a, 443, 5555, "SA"), (a, b, 5555, 443, "A"), (a, b, 5555, 443, "PA")]
    ):
        p = Ether() / IPv6(src=s, dst=d, hlim=60) / TCP(sport=sp, dport=dp, flags=fl)
        if fl == "PA":
            p = p / Raw(b"hello")
        p.time = T0 + t0 + 0.01 * k
        out.append(p)
    return out


def write(path: Path, packets, linktype=None) -> Path:
    wrpcap(str(path), packets, linktype=linktype)
    return path


def write_pcapng(path: Path, packets) -> Path:
    with PcapNgWriter(str(path)) as w:
        for p in packets:
            w.write(p)
    return path


def sll(t, src, dst, sport, dport, flags):
    return tcp(t, src, dst, sport, dport, flags,
               l2=lambda: CookedLinux(proto=0x0800, pkttype=0, lladdrtype=1, lladdrlen=6))


def vlan_tcp(t, src, dst, sport, dport, flags):
    return tcp(t, src, dst, sport, dport, flags, l2=lambda: Ether() / Dot1Q(vlan=5))
