"""Vectorised protocol decoding: link layer -> IPv4/IPv6 -> TCP/UDP/ICMP, all records at once.

Every header field is gathered with numpy fancy indexing over a block's buffer (no per-packet
Python). Reads are guarded by the captured length, so a snap-length-truncated packet never
borrows bytes from the next record. What cannot be decoded is dropped AND counted in
`DecodeStats`, which the command line reports on stderr:
- `dropped_short`: the IP header itself was not captured (snap length below link + IP header);
- `l4_cut`: the transport header was cut by the snap length (TCP needs its first 14 bytes, up to
  the flags; UDP its 4 bytes of ports), so ports or flags are unknown and the packet cannot be
  put in its flow (ports 0 would merge unrelated conversations);
- `null_unknown`: a DLT_NULL/LOOP packet whose 4-byte family field matches no address family
  or Ethernet type in either byte order;
- `dropped_non_ip`: other non-IP frames (ARP, LLDP, ...), as nfstream and tshark's `ip` filter.
IPv6 TCP at snap length 68 (Ethernet 14 + IPv6 40 + 14 bytes of TCP) keeps ports and flags.

ICMP errors (IPv4 types 3/4/5/11/12, ICMPv6 1-4) quote the packet that caused them (RFC 792: its
IP header and the first 8 bytes of its transport header; RFC 4443: as much as fits). The quote's
identity is kept in the `q_*` columns (protocol, low address words, ports, IP id, TTL, TCP seq),
so the ground truth can tie an error to the very packet it answers (`uavcas.attacks`: provoked
packets); they are 0 for every other packet and for an error whose quote (IP header + 8 bytes)
was not captured. A quoted IPv6 packet's extension headers are not walked: its `q_proto` is then
the first extension header and its ports stay 0.

MAVLink (`mav_msgid`): the message id of the first MAVLink frame a UDP datagram starts with, -1
for every other packet. Decoded here, vectorised like every other field, from the frame header
alone (MAVLink 2, 0xFD: len at byte 1, incompat_flags at byte 2, the 24-bit id little-endian at
bytes 7-9, frame = 10 + len + 2 CRC (+ 13 signature when incompat_flags bit 0 is set); MAVLink 1,
0xFE: len at byte 1, the 8-bit id at byte 5, frame = 6 + len + 2), validated by the magic byte, no
unknown incompat flag, and the frame fitting inside the datagram's UDP length. Not by its CRC:
that needs each message's CRC_EXTRA and a per-packet checksum, i.e. pymavlink per message, which
on a run's hundreds of thousands of packets is the slow path; `uavcas.mavlink_capture` does parse
every MAVLink datagram with pymavlink (CRC checked) for users. The ground truth needs which
message a datagram carries (a spoofed position report), not its fields.

IP fragments: the first fragment carries the transport header; later fragments are marked
(`frag` 2) and get their datagram's ports in `uavcas.flows.fragments`.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .pcapio import RawCapture

# LINKTYPE_* values (https://www.tcpdump.org/linktypes.html)
LT_NULL, LT_ETHERNET, LT_RAW_A, LT_RAW_B, LT_RAW, LT_LOOP = 0, 1, 12, 14, 101, 108
LT_SLL, LT_IPV4, LT_IPV6, LT_SLL2 = 113, 228, 229, 276
SUPPORTED_LINKTYPES = (LT_NULL, LT_ETHERNET, LT_RAW_A, LT_RAW_B, LT_RAW, LT_LOOP, LT_SLL, LT_IPV4, LT_IPV6, LT_SLL2)
ETH_IPV4, ETH_IPV6 = 0x0800, 0x86DD
# BSD address-family values of IPv6 in a DLT_NULL header: Linux 10, NetBSD/OpenBSD 24,
# FreeBSD 28, Darwin 30 (tcpdump's BSD_AFNUM_INET6_*); IPv4 is 2 everywhere.
AF_INET, AF_INET6 = (2,), (10, 24, 28, 30)
IPV4_MAPPED = np.uint64(0x0000FFFF00000000)  # IPv4 a.b.c.d is stored as ::ffff:a.b.c.d
IPV6_EXT_HEADERS = (0, 43, 60)  # hop-by-hop, routing, destination options (length in 8-octet units)
IPV6_FRAGMENT = 44
TCP_MIN_CAPTURED, UDP_MIN_CAPTURED = 14, 4  # bytes of L4 header needed: TCP through its flags, UDP ports
FRAG_NONE, FRAG_FIRST, FRAG_LATER = 0, 1, 2
ICMP4_ERRORS = (3, 4, 5, 11, 12)  # unreachable, source quench, redirect, time exceeded, parameter problem
ICMP6_ERRORS = (1, 2, 3, 4)  # unreachable, packet too big, time exceeded, parameter problem
ICMP_HEADER = 8  # type, code, checksum, 4 bytes of unused / MTU / pointer: the quote follows
MAV_V1_MAGIC, MAV_V2_MAGIC = 0xFE, 0xFD  # MAVLink frame start markers (mavlink.io, serialization)
MAV_V2_SIGNED = 0x01  # MAVLINK_IFLAG_SIGNED, the only incompat flag MAVLink 2 defines


@dataclass(frozen=True)
class DecodeStats:
    records: int
    ip_packets: int
    dropped_non_ip: int
    dropped_short: int
    unsupported_linktypes: tuple[int, ...]
    l4_cut: int = 0
    null_unknown: int = 0
    snaplen: int = 0


class _Gather:
    """Big-endian field reads at per-packet byte offsets.

    A read that would run past the buffer is moved back inside it; its value is garbage, but every
    caller discards fields beyond a record's captured length, so a valid field is never moved.
    """

    def __init__(self, buf: np.ndarray):
        self.buf = buf
        self.size = buf.shape[0]

    def u8(self, pos: np.ndarray) -> np.ndarray:
        return self.buf[np.minimum(pos, self.size - 1)]

    def be(self, pos: np.ndarray, width: int) -> np.ndarray:
        b = self.buf[np.minimum(pos, self.size - width)[:, None] + np.arange(width)]
        return np.ascontiguousarray(b).view(f">u{width}").ravel()


def _null_ethertype(g: _Gather, off: np.ndarray) -> np.ndarray:
    """Ethernet type of DLT_NULL / LOOP records, whatever byte order wrote the family field.

    The field is an address family in the capturing host's byte order (tcpdump: if the upper 16
    bits are set, swap). Some systems put an Ethernet type there instead, either as the value or
    in its last two bytes (Cisco-HDLC-like `0f 00 08 00`); all of these are accepted.
    """
    be = g.be(off, 4).astype(np.int64)
    le = g.be(off, 4).byteswap().astype(np.int64)
    fam = np.where((le & 0xFFFF0000) == 0, le, be)
    low = be & 0xFFFF
    v4 = np.isin(fam, AF_INET) | (fam == ETH_IPV4) | (low == ETH_IPV4)
    v6 = np.isin(fam, AF_INET6) | (fam == ETH_IPV6) | (low == ETH_IPV6)
    return np.where(v4, ETH_IPV4, np.where(v6, ETH_IPV6, 0))


def _icmp_quotes(g: _Gather, l4: np.ndarray, end: np.ndarray, proto: np.ndarray, v4: np.ndarray,
                 icmp: np.ndarray) -> dict[str, np.ndarray]:
    """The `q_*` columns: the identity of the packet an ICMP error quotes (module docstring).

    Only the low 64-bit address words are kept: IPv4 addresses whole (stored IPv4-mapped, as the
    table's own), IPv6 their interface half, which with the ports, IP id, seq and the error's own
    destination (the quoted source) tells one packet from another without two more columns.
    """
    m = l4.shape[0]
    out = {"q_proto": np.zeros(m, dtype=np.uint8), "q_src_lo": np.zeros(m, dtype=np.uint64),
           "q_dst_lo": np.zeros(m, dtype=np.uint64), "q_sport": np.zeros(m, dtype=np.uint16),
           "q_dport": np.zeros(m, dtype=np.uint16), "q_ip_id": np.zeros(m, dtype=np.uint32),
           "q_ttl": np.zeros(m, dtype=np.uint8), "q_tcp_seq": np.zeros(m, dtype=np.uint32)}
    if not icmp.any():
        return out
    typ = g.u8(l4).astype(np.int64)
    err = icmp & np.where(v4, (proto == 1) & np.isin(typ, ICMP4_ERRORS), (proto == 58) & np.isin(typ, ICMP6_ERRORS))
    q = l4 + ICMP_HEADER
    b0 = g.u8(q)
    ihl = (b0 & 0x0F).astype(np.int64) * 4
    # a quote is used only when its IP header and the 8 transport bytes after it were captured
    q4 = err & (b0 >> 4 == 4) & (ihl >= 20) & (q + ihl + 8 <= end)
    q6 = err & (b0 >> 4 == 6) & (q + 40 + 8 <= end)
    ql4 = np.zeros(m, dtype=np.int64)
    qproto = np.zeros(m, dtype=np.int64)
    first = np.zeros(m, dtype=bool)  # the quoted packet carries its transport header
    if q4.any():
        p = q[q4]
        qproto[q4] = g.u8(p + 9)
        out["q_ttl"][q4] = g.u8(p + 8)
        out["q_ip_id"][q4] = g.be(p + 4, 2)
        out["q_src_lo"][q4] = g.be(p + 12, 4).astype(np.uint64) | IPV4_MAPPED
        out["q_dst_lo"][q4] = g.be(p + 16, 4).astype(np.uint64) | IPV4_MAPPED
        first[q4] = (g.be(p + 6, 2).astype(np.int64) & 0x1FFF) == 0
        ql4[q4] = p + ihl[q4]
    if q6.any():
        p = q[q6]
        qproto[q6] = g.u8(p + 6)
        out["q_ttl"][q6] = g.u8(p + 7)
        out["q_src_lo"][q6] = g.be(p + 16, 8)
        out["q_dst_lo"][q6] = g.be(p + 32, 8)
        first[q6] = True
        ql4[q6] = p + 40
    out["q_proto"] = qproto.astype(np.uint8)
    ports = first & ((qproto == 6) | (qproto == 17))
    if ports.any():
        out["q_sport"][ports] = g.be(ql4[ports], 2)
        out["q_dport"][ports] = g.be(ql4[ports] + 2, 2)
    tcp = first & (qproto == 6)
    if tcp.any():
        out["q_tcp_seq"][tcp] = g.be(ql4[tcp] + 4, 4)
    return out


def _mavlink_msgid(g: _Gather, l4: np.ndarray, end: np.ndarray, udp: np.ndarray) -> np.ndarray:
    """`mav_msgid` (module docstring): the first frame's message id, -1 where there is none."""
    out = np.full(l4.shape[0], -1, dtype=np.int32)
    q = l4 + 8  # the UDP payload
    cand = udp & (q + 6 <= end)
    if not cand.any():
        return out
    idx = np.flatnonzero(cand)
    p = q[idx]
    room = g.be(l4[idx] + 4, 2).astype(np.int64) - 8  # the datagram's payload, from the UDP length
    magic, plen = g.u8(p), g.u8(p + 1).astype(np.int64)
    v1 = (magic == MAV_V1_MAGIC) & (6 + plen + 2 <= room)
    flags = g.u8(p + 2).astype(np.int64)
    v2 = ((magic == MAV_V2_MAGIC) & (p + 10 <= end[idx]) & ((flags & ~MAV_V2_SIGNED) == 0)
          & (10 + plen + 2 + np.where(flags & MAV_V2_SIGNED, 13, 0) <= room))
    out[idx[v1]] = g.u8(p[v1] + 5)
    out[idx[v2]] = (g.u8(p[v2] + 7).astype(np.int32) | (g.u8(p[v2] + 8).astype(np.int32) << 8)
                    | (g.u8(p[v2] + 9).astype(np.int32) << 16))
    return out


def link_layer(raw: RawCapture, g: "_Gather | None" = None) -> tuple[np.ndarray, np.ndarray, int]:
    """Per record of `raw`: the Ethernet type of its network layer (0: not IP, or a DLT_NULL
    family no table knows), the buffer offset of its network-layer header, and the number of
    DLT_NULL/LOOP records whose family field was unknown. Shared by `decode` and the readers
    that need a packet's bytes above the link layer (`uavcas.flows.mavlink`)."""
    g = g if g is not None else _Gather(raw.buf)
    off = raw.data_off
    lt = raw.linktype
    n = off.shape[0]
    ethertype = np.zeros(n, dtype=np.int64)
    l3 = off.copy()

    eth = lt == LT_ETHERNET
    if eth.any():
        et = g.be(off[eth] + 12, 2).astype(np.int64)
        pos = off[eth] + 14
        for _ in range(2):  # up to two VLAN / QinQ tags
            vlan = (et == 0x8100) | (et == 0x88A8)
            if not vlan.any():
                break
            et[vlan] = g.be(pos[vlan] + 2, 2)
            pos[vlan] += 4
        ethertype[eth], l3[eth] = et, pos
    sll = lt == LT_SLL
    if sll.any():
        ethertype[sll], l3[sll] = g.be(off[sll] + 14, 2), off[sll] + 16
    sll2 = lt == LT_SLL2
    if sll2.any():
        ethertype[sll2], l3[sll2] = g.be(off[sll2], 2), off[sll2] + 20
    bsd = (lt == LT_NULL) | (lt == LT_LOOP)
    null_unknown = 0
    if bsd.any():
        ethertype[bsd] = _null_ethertype(g, off[bsd])
        l3[bsd] = off[bsd] + 4
        null_unknown = int((ethertype[bsd] == 0).sum())
    raw_ip = np.isin(lt, (LT_RAW_A, LT_RAW_B, LT_RAW, LT_IPV4, LT_IPV6))
    if raw_ip.any():
        ver = g.u8(off[raw_ip]) >> 4
        ethertype[raw_ip] = np.where(ver == 4, ETH_IPV4, np.where(ver == 6, ETH_IPV6, 0))
    return ethertype, l3, null_unknown


def decode(raw: RawCapture) -> tuple[dict[str, np.ndarray], DecodeStats]:
    """Decode all records of `raw`; returns per-IP-packet columns (see PacketTable) and stats."""
    g = _Gather(raw.buf)
    off = raw.data_off
    end = off + raw.cap_len.astype(np.int64)
    lt = raw.linktype
    n = off.shape[0]
    ethertype, l3, null_unknown = link_layer(raw, g)
    unsupported = tuple(sorted(set(np.unique(lt).tolist()) - set(SUPPORTED_LINKTYPES)))

    b0 = g.u8(l3)  # version and IHL share the first byte: gather it once
    version = b0 >> 4
    is4 = (ethertype == ETH_IPV4) & (version == 4)
    is6 = (ethertype == ETH_IPV6) & (version == 6)
    ihl = (b0 & 0x0F).astype(np.int64) * 4
    full4 = is4 & (ihl >= 20) & (l3 + ihl <= end)
    full6 = is6 & (l3 + 40 <= end)
    keep = full4 | full6
    short = int(((is4 | is6) & ~keep).sum())
    idx = np.flatnonzero(keep)
    l3, end, ihl = l3[idx], end[idx], ihl[idx]
    wire_l3 = raw.wire_len[idx].astype(np.int64) - (l3 - off[idx])  # IP bytes on the wire
    v4 = full4[idx]
    v6 = ~v4
    m = idx.shape[0]

    proto = np.zeros(m, dtype=np.int64)
    ttl = np.zeros(m, dtype=np.uint8)
    ip_id = np.zeros(m, dtype=np.uint32)
    ip_len = np.zeros(m, dtype=np.int64)
    frag_off = np.zeros(m, dtype=np.int64)
    more = np.zeros(m, dtype=bool)
    src_hi = np.zeros(m, dtype=np.uint64)
    src_lo = np.zeros(m, dtype=np.uint64)
    dst_hi = np.zeros(m, dtype=np.uint64)
    dst_lo = np.zeros(m, dtype=np.uint64)
    l4 = l3.copy()

    if v4.any():
        p = l3[v4]
        proto[v4] = g.u8(p + 9)
        ttl[v4] = g.u8(p + 8)
        ip_id[v4] = g.be(p + 4, 2)
        ip_len[v4] = g.be(p + 2, 2)
        fw = g.be(p + 6, 2).astype(np.int64)
        frag_off[v4], more[v4] = fw & 0x1FFF, (fw & 0x2000) != 0
        src_lo[v4] = g.be(p + 12, 4).astype(np.uint64) | IPV4_MAPPED
        dst_lo[v4] = g.be(p + 16, 4).astype(np.uint64) | IPV4_MAPPED
        l4[v4] = p + ihl[v4]
    if v6.any():
        p = l3[v6]
        ttl[v6] = g.u8(p + 7)  # hop limit
        ip_len[v6] = 40 + g.be(p + 4, 2).astype(np.int64)
        src_hi[v6], src_lo[v6] = g.be(p + 8, 8), g.be(p + 16, 8)
        dst_hi[v6], dst_lo[v6] = g.be(p + 24, 8), g.be(p + 32, 8)
        nh = g.u8(p + 6).astype(np.int64)
        pos = p + 40
        f_off = np.zeros(p.shape[0], dtype=np.int64)
        f_more = np.zeros(p.shape[0], dtype=bool)
        f_id = np.zeros(p.shape[0], dtype=np.uint32)
        e = end[v6]
        for _ in range(4):  # a few extension headers; real traffic rarely chains more
            ext = np.isin(nh, IPV6_EXT_HEADERS) & (pos + 8 <= e)
            frag = (nh == IPV6_FRAGMENT) & (pos + 8 <= e)
            if not (ext.any() or frag.any()):
                break
            step = np.where(ext, (g.u8(pos + 1).astype(np.int64) + 1) * 8, np.where(frag, 8, 0))
            fw = g.be(pos + 2, 2).astype(np.int64)
            f_off = np.where(frag, fw >> 3, f_off)
            f_more = np.where(frag, (fw & 1) != 0, f_more)
            f_id = np.where(frag, g.be(pos + 4, 4), f_id)
            nh = np.where(ext | frag, g.u8(pos).astype(np.int64), nh)
            pos = pos + step
        proto[v6], l4[v6], frag_off[v6], more[v6], ip_id[v6] = nh, pos, f_off, f_more, f_id
    # IPv4 total length 0 (TSO) or shorter than the header: fall back to the wire length
    ip_len = np.where(ip_len >= (l4 - l3), ip_len, wire_l3)

    first_frag = frag_off == 0  # later fragments carry no L4 header
    captured_l4 = end - l4
    tcp = (proto == 6) & first_frag
    udp = (proto == 17) & first_frag
    cut = (tcp & (captured_l4 < TCP_MIN_CAPTURED)) | (udp & (captured_l4 < UDP_MIN_CAPTURED))
    tcp &= ~cut
    udp &= ~cut
    icmp = ((proto == 1) | (proto == 58)) & first_frag
    sport = np.zeros(m, dtype=np.uint16)
    dport = np.zeros(m, dtype=np.uint16)
    flags = np.zeros(m, dtype=np.uint16)
    seq = np.zeros(m, dtype=np.uint32)
    ack = np.zeros(m, dtype=np.uint32)
    l4_hdr = np.zeros(m, dtype=np.uint16)
    ports = tcp | udp
    if ports.any():
        sport[ports] = g.be(l4[ports], 2)
        dport[ports] = g.be(l4[ports] + 2, 2)
    if tcp.any():
        q = l4[tcp]
        b12 = g.u8(q + 12).astype(np.uint16)
        seq[tcp] = g.be(q + 4, 4)
        ack[tcp] = g.be(q + 8, 4)
        flags[tcp] = g.u8(q + 13).astype(np.uint16) | ((b12 & 1) << 8)  # NS bit as 0x100
        l4_hdr[tcp] = (b12 >> 4) * 4
    l4_hdr[udp | icmp] = 8
    quote = _icmp_quotes(g, l4, end, proto, v4, icmp & (captured_l4 >= ICMP_HEADER))
    frag = np.where(frag_off > 0, FRAG_LATER, np.where(more, FRAG_FIRST, FRAG_NONE)).astype(np.uint8)

    ok = ~cut
    cols = {
        "ts_ns": raw.ts_ns[idx],
        "frame_len": raw.wire_len[idx],
        "cap_len": raw.cap_len[idx],
        "ip_version": np.where(v4, 4, 6).astype(np.uint8),
        "src_hi": src_hi,
        "src_lo": src_lo,
        "dst_hi": dst_hi,
        "dst_lo": dst_lo,
        "sport": sport,
        "dport": dport,
        "proto": proto.astype(np.uint8),
        "tcp_flags": flags,
        "ttl": ttl,
        "ip_id": ip_id,
        "tcp_seq": seq,
        "tcp_ack": ack,
        "ip_len": ip_len.astype(np.uint32),
        "ip_hdr_len": (l4 - l3).astype(np.uint16),
        "l4_hdr_len": l4_hdr,
        "frame_index": idx.astype(np.int64) + raw.first_record,
        **quote,
        "mav_msgid": _mavlink_msgid(g, l4, end, udp),
        "frag": frag,
    }
    if cut.any():
        cols = {k: v[ok] for k, v in cols.items()}
    n_cut = int(cut.sum())
    stats = DecodeStats(
        records=n,
        ip_packets=m - n_cut,
        dropped_non_ip=int(n - m - short),
        dropped_short=short,
        unsupported_linktypes=unsupported,
        l4_cut=n_cut,
        null_unknown=null_unknown,
        snaplen=raw.snaplen,
    )
    return cols, stats
