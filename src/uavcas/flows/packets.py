"""The packet table: one row per IP packet of one or more captures, as numpy columns.

Columns (all numpy arrays of equal length):
  ts_ns int64 (Unix nanoseconds, exact), frame_len uint32 (wire length, tshark frame.len), cap_len
  uint32, ip_version uint8 (4/6), src_hi/src_lo/dst_hi/dst_lo uint64 (the 128-bit address; IPv4
  is stored IPv4-mapped ::ffff:a.b.c.d so both families share one key), sport/dport uint16 (a later
  IP fragment carries its datagram's ports, `uavcas.flows.fragments`), proto uint8, tcp_flags
  uint16 (FIN 0x01 SYN 0x02 RST 0x04 PSH 0x08 ACK 0x10 URG 0x20 ECE 0x40 CWR 0x80 NS 0x100), ttl
  uint8 (hop limit for IPv6), ip_id uint32 (IPv6: fragment id or 0), tcp_seq uint32, tcp_ack
  uint32 (the acknowledgement field; meaningful with ACK set, 0 outside TCP), ip_len uint32
  (IP total length from the header: bytes on the wire above the link layer, whatever the snap
  length), ip_hdr_len/l4_hdr_len uint16 (parsed header bytes, incl. options / extension headers;
  l4 0 for later fragments), frame_index int64 (record number in its file), point int16 (index
  into `points`); for ICMP errors the packet they quote (`QUOTE_COLUMNS`, 0 for other packets,
  `uavcas.flows.decode`): q_proto uint8, q_src_lo/q_dst_lo uint64 (the low address words),
  q_sport/q_dport uint16, q_ip_id uint32, q_ttl uint8, q_tcp_seq uint32; mav_msgid int32 (the
  message id of the MAVLink frame a UDP datagram starts with, -1 for any other packet: the
  header is decoded and validated in `uavcas.flows.decode`).
`table["ts_s"]` gives float64 seconds for convenience (derived, rounded to ~0.2 us at today's
epoch); computations that need exact time use `ts_ns`.

Captures are read a block at a time (`iter_packet_blocks`), so a file is never held whole in
memory; `read_packets` concatenates the decoded blocks of all files.
"""

from __future__ import annotations

import ipaddress
from collections.abc import Iterator, Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pandas as pd

from .decode import DecodeStats, decode
from .fragments import FragmentResolver
from .pcapio import CHUNK_BYTES, CaptureError, iter_capture

COLUMNS: tuple[str, ...] = (
    "ts_ns", "frame_len", "cap_len", "ip_version", "src_hi", "src_lo", "dst_hi", "dst_lo",
    "sport", "dport", "proto", "tcp_flags", "ttl", "ip_id", "tcp_seq", "tcp_ack", "ip_len", "ip_hdr_len",
    "l4_hdr_len", "frame_index", "point",
    "q_proto", "q_src_lo", "q_dst_lo", "q_sport", "q_dport", "q_ip_id", "q_ttl", "q_tcp_seq", "mav_msgid",
)  # fmt: skip
QUOTE_COLUMNS: tuple[str, ...] = COLUMNS[COLUMNS.index("q_proto"):COLUMNS.index("mav_msgid")]
NO_MAVLINK = -1  # mav_msgid of a packet that carries no MAVLink frame (0 is HEARTBEAT's id)
# what a column a hand-built row leaves out holds (0 unless 0 means something)
_ABSENT: dict[str, int] = {"mav_msgid": NO_MAVLINK}
ETHERNET_HEADER = 14


@dataclass(frozen=True)
class Truncation:
    path: str
    offset: int


@dataclass
class CaptureStats:
    """What one capture file held and what could not be used (summed over its blocks)."""

    path: str
    records: int = 0
    ip_packets: int = 0
    dropped_non_ip: int = 0
    dropped_short: int = 0
    l4_cut: int = 0
    null_unknown: int = 0
    orphan_fragments: int = 0
    snaplen: int = 0
    unsupported_linktypes: tuple[int, ...] = ()

    def add(self, st: DecodeStats) -> None:
        self.records += st.records
        self.ip_packets += st.ip_packets
        self.dropped_non_ip += st.dropped_non_ip
        self.dropped_short += st.dropped_short
        self.l4_cut += st.l4_cut
        self.null_unknown += st.null_unknown
        self.snaplen = st.snaplen
        self.unsupported_linktypes = tuple(sorted(set(self.unsupported_linktypes) | set(st.unsupported_linktypes)))

    def warnings(self) -> list[str]:
        """One line per kind of packet that was left out (for stderr)."""
        snap = f" (snap length {self.snaplen} bytes)" if self.snaplen else ""
        out = []
        if self.l4_cut:
            out.append(f"{self.path}: {self.l4_cut} of {self.records} packets had their transport header cut by the "
                       f"snap length{snap}; ports/flags unknown, left out of the flows")  # fmt: skip
        if self.dropped_short:
            out.append(f"{self.path}: {self.dropped_short} of {self.records} packets had their IP header cut by the "
                       f"snap length{snap}; left out")  # fmt: skip
        if self.null_unknown:
            out.append(f"{self.path}: {self.null_unknown} DLT_NULL/LOOP packets with an unknown family field; left out")
        if self.orphan_fragments:
            out.append(f"{self.path}: {self.orphan_fragments} IP fragments whose first fragment is not in the capture; "
                       "left out of the flows")  # fmt: skip
        return out


@dataclass
class PacketTable:
    cols: dict[str, np.ndarray]
    points: tuple[str, ...]  # capture point names, indexed by cols["point"]
    stats: list[CaptureStats] = field(default_factory=list)
    truncations: list[Truncation] = field(default_factory=list)

    def __post_init__(self) -> None:
        c = self.cols
        # Tables built by hand (synthetic flows, tests) may give float seconds and no IP length.
        if "ts_ns" not in c and "ts_s" in c:
            c["ts_ns"] = np.round(np.asarray(c.pop("ts_s"), dtype=np.float64) * 1e9).astype(np.int64)
        if "ip_len" not in c and "frame_len" in c:
            c["ip_len"] = np.maximum(np.asarray(c["frame_len"]).astype(np.int64) - ETHERNET_HEADER, 0).astype(np.uint32)
        self._ts_s: np.ndarray | None = None

    def __len__(self) -> int:
        return int(self.cols["ts_ns"].shape[0])

    def __getitem__(self, name: str) -> np.ndarray:
        if name == "ts_s":
            if self._ts_s is None:
                self._ts_s = ns_to_s(self.cols["ts_ns"])
            return self._ts_s
        return self.cols[name]

    def take(self, idx: np.ndarray) -> "PacketTable":
        return PacketTable({k: v[idx] for k, v in self.cols.items()}, self.points, self.stats, self.truncations)

    def to_pandas(self) -> pd.DataFrame:
        """Readable frame: addresses as strings, capture point names (for inspection and tests)."""
        df = pd.DataFrame({k: v for k, v in self.cols.items() if k not in ("src_hi", "src_lo", "dst_hi", "dst_lo")})
        df.insert(1, "ts_s", self["ts_s"])
        df.insert(5, "src_ip", addresses_to_str(self.cols["src_hi"], self.cols["src_lo"]))
        df.insert(6, "dst_ip", addresses_to_str(self.cols["dst_hi"], self.cols["dst_lo"]))
        df["point"] = np.asarray(self.points, dtype=object)[self.cols["point"]] if len(df) else []
        return df


def ns_to_s(ns: np.ndarray) -> np.ndarray:
    """int64 ns -> float64 s, correctly rounded for epoch times (whole seconds are exact)."""
    ns = np.asarray(ns, dtype=np.int64)
    sec = ns // 1_000_000_000
    return sec.astype(np.float64) + (ns - sec * 1_000_000_000).astype(np.float64) / 1e9


def empty_columns() -> dict[str, np.ndarray]:
    dtypes = {"ts_ns": np.int64, "frame_len": np.uint32, "cap_len": np.uint32, "ip_version": np.uint8,
              "src_hi": np.uint64, "src_lo": np.uint64, "dst_hi": np.uint64, "dst_lo": np.uint64,
              "sport": np.uint16, "dport": np.uint16, "proto": np.uint8, "tcp_flags": np.uint16, "ttl": np.uint8,
              "ip_id": np.uint32, "tcp_seq": np.uint32, "tcp_ack": np.uint32, "ip_len": np.uint32,
              "ip_hdr_len": np.uint16,
              "l4_hdr_len": np.uint16, "frame_index": np.int64, "point": np.int16,
              "q_proto": np.uint8, "q_src_lo": np.uint64, "q_dst_lo": np.uint64, "q_sport": np.uint16,
              "q_dport": np.uint16, "q_ip_id": np.uint32, "q_ttl": np.uint8, "q_tcp_seq": np.uint32,
              "mav_msgid": np.int32}  # fmt: skip
    return {c: np.zeros(0, dtype=dtypes[c]) for c in COLUMNS}


def table_from_rows(rows: Sequence[dict], points: Sequence[str]) -> "PacketTable":
    """A packet table from one dict per packet (column -> value); a column a row leaves out is 0
    (mav_msgid: -1, no MAVLink). For tests and generated traffic: captures are read with `read_packets`."""
    empty = empty_columns()
    unknown = {k for r in rows for k in r} - set(COLUMNS)
    if unknown:
        raise ValueError(f"unknown packet columns {sorted(unknown)}")
    cols = {c: np.array([r.get(c, _ABSENT.get(c, 0)) for r in rows], dtype=empty[c].dtype) for c in COLUMNS}
    return PacketTable(cols, tuple(points))


def iter_packet_blocks(
    path: str | Path, point: int, stats: CaptureStats, truncations: list[Truncation],
    allow_truncated: bool = False, chunk_bytes: int = CHUNK_BYTES,
) -> Iterator[dict[str, np.ndarray]]:  # fmt: skip
    """Decoded packet columns of one capture file, a block at a time (fragments resolved).

    `stats` and `truncations` are filled as the blocks go by.
    """
    frags = FragmentResolver()
    blocks = iter_capture(path, allow_truncated=allow_truncated, chunk_bytes=chunk_bytes)
    raw = next(blocks, None)
    while raw is not None:
        nxt = next(blocks, None)
        cols, st = decode(raw)
        stats.add(st)
        if st.unsupported_linktypes and stats.ip_packets == 0 and stats.records and nxt is None:
            raise CaptureError(f"{path}: unsupported link type(s) {list(st.unsupported_linktypes)} at byte offset 20")
        if raw.truncated_at is not None:
            truncations.append(Truncation(str(path), raw.truncated_at))
        cols = frags.resolve(cols, final=nxt is None)
        del cols["frag"]
        cols["point"] = np.full(cols["ts_ns"].shape[0], point, dtype=np.int16)
        yield cols
        raw = nxt
    stats.orphan_fragments = frags.orphans


def read_packets(
    paths: Sequence[str | Path],
    points: Sequence[str] | None = None,
    allow_truncated: bool = False,
    chunk_bytes: int = CHUNK_BYTES,
) -> PacketTable:
    """Read captures into one table; `points` names each file's capture point (default: file stem)."""
    paths = [Path(p) for p in paths]
    names = tuple(points) if points is not None else tuple(p.stem for p in paths)
    if len(names) != len(paths):
        raise ValueError("one capture point name per capture file is needed")
    parts: list[dict[str, np.ndarray]] = []
    stats: list[CaptureStats] = []
    truncs: list[Truncation] = []
    for k, path in enumerate(paths):
        st = CaptureStats(str(path))
        stats.append(st)
        parts.extend(iter_packet_blocks(path, k, st, truncs, allow_truncated, chunk_bytes))
    merged = {c: np.concatenate([p[c] for p in parts]) for c in COLUMNS} if parts else empty_columns()
    return PacketTable(merged, names, stats, truncs)


def payload_and_header(
    proto: np.ndarray, ip_len: np.ndarray, ip_hdr: np.ndarray, l4_hdr: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Per packet: L4 payload bytes and L4 header bytes as CICFlowMeter counts them
    (`PacketReader`): TCP/UDP only, 0 for other protocols, whose headers it does not parse."""
    l4 = (proto == 6) | (proto == 17)
    payload = ip_len.astype(np.int64) - ip_hdr.astype(np.int64) - l4_hdr.astype(np.int64)
    return np.where(l4, np.maximum(payload, 0), 0), np.where(l4, l4_hdr.astype(np.int64), 0)


def addresses_to_str(hi: np.ndarray, lo: np.ndarray) -> np.ndarray:
    """128-bit addresses -> strings ('10.0.0.1' for IPv4-mapped, compressed IPv6 otherwise).

    Formats each distinct address once, so it is cheap even for millions of packets.
    """
    if hi.shape[0] == 0:
        return np.zeros(0, dtype=object)
    pair = np.stack([hi, lo], axis=1)
    uniq, inv = np.unique(pair, axis=0, return_inverse=True)
    text = np.empty(uniq.shape[0], dtype=object)
    for i, (h, l) in enumerate(uniq.tolist()):
        if h == 0 and (l >> 32) == 0xFFFF:
            text[i] = str(ipaddress.IPv4Address(l & 0xFFFFFFFF))
        else:
            text[i] = str(ipaddress.IPv6Address((h << 64) | l))
    return text[inv.ravel()]


def address_to_words(text: str) -> tuple[int, int]:
    """'10.0.0.1' or an IPv6 string -> (hi, lo) as stored in the packet table."""
    addr = ipaddress.ip_address(text)
    if addr.version == 4:
        return 0, 0x0000FFFF00000000 | int(addr)
    v = int(addr)
    return v >> 64, v & 0xFFFFFFFFFFFFFFFF
