"""The packet table: one row per IP packet of one or more captures, as numpy columns.

Columns (all numpy arrays of equal length):
  ts_s float64 (Unix seconds), frame_len uint32 (wire length, tshark frame.len), cap_len uint32,
  ip_version uint8 (4/6), src_hi/src_lo/dst_hi/dst_lo uint64 (the 128-bit address; IPv4 is stored
  IPv4-mapped ::ffff:a.b.c.d so both families share one key), sport/dport uint16, proto uint8,
  tcp_flags uint16 (FIN 0x01 SYN 0x02 RST 0x04 PSH 0x08 ACK 0x10 URG 0x20 ECE 0x40 CWR 0x80
  NS 0x100), ttl uint8 (hop limit for IPv6), ip_id uint32 (IPv6: fragment id or 0), tcp_seq uint32,
  ip_hdr_len/l4_hdr_len uint16 (parsed header bytes, incl. options / extension headers),
  frame_index int64 (record number in its file), point int16 (index into `points`).
"""

from __future__ import annotations

import ipaddress
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pandas as pd

from .decode import DecodeStats, decode
from .pcapio import CaptureError, read_capture

COLUMNS: tuple[str, ...] = (
    "ts_s", "frame_len", "cap_len", "ip_version", "src_hi", "src_lo", "dst_hi", "dst_lo",
    "sport", "dport", "proto", "tcp_flags", "ttl", "ip_id", "tcp_seq", "ip_hdr_len",
    "l4_hdr_len", "frame_index", "point",
)  # fmt: skip


@dataclass(frozen=True)
class Truncation:
    path: str
    offset: int


@dataclass
class PacketTable:
    cols: dict[str, np.ndarray]
    points: tuple[str, ...]  # capture point names, indexed by cols["point"]
    stats: list[DecodeStats] = field(default_factory=list)
    truncations: list[Truncation] = field(default_factory=list)

    def __len__(self) -> int:
        return int(self.cols["ts_s"].shape[0])

    def __getitem__(self, name: str) -> np.ndarray:
        return self.cols[name]

    def take(self, idx: np.ndarray) -> "PacketTable":
        return PacketTable({k: v[idx] for k, v in self.cols.items()}, self.points, self.stats, self.truncations)

    def to_pandas(self) -> pd.DataFrame:
        """Readable frame: addresses as strings, capture point names (for inspection and tests)."""
        df = pd.DataFrame({k: v for k, v in self.cols.items() if k not in ("src_hi", "src_lo", "dst_hi", "dst_lo")})
        df.insert(4, "src_ip", addresses_to_str(self.cols["src_hi"], self.cols["src_lo"]))
        df.insert(5, "dst_ip", addresses_to_str(self.cols["dst_hi"], self.cols["dst_lo"]))
        df["point"] = np.asarray(self.points, dtype=object)[self.cols["point"]] if len(df) else []
        return df


def read_packets(
    paths: Sequence[str | Path],
    points: Sequence[str] | None = None,
    allow_truncated: bool = False,
) -> PacketTable:
    """Read captures into one table; `points` names each file's capture point (default: file stem)."""
    paths = [Path(p) for p in paths]
    names = tuple(points) if points is not None else tuple(p.stem for p in paths)
    if len(names) != len(paths):
        raise ValueError("one capture point name per capture file is needed")
    parts: list[dict[str, np.ndarray]] = []
    stats: list[DecodeStats] = []
    truncs: list[Truncation] = []
    for k, path in enumerate(paths):
        raw = read_capture(path, allow_truncated=allow_truncated)
        cols, st = decode(raw)
        if st.unsupported_linktypes and st.ip_packets == 0 and st.records:
            raise CaptureError(f"{path}: unsupported link type(s) {list(st.unsupported_linktypes)} at byte offset 20")
        cols["point"] = np.full(cols["ts_s"].shape[0], k, dtype=np.int16)
        parts.append(cols)
        stats.append(st)
        if raw.truncated_at is not None:
            truncs.append(Truncation(str(path), raw.truncated_at))
    if parts:
        merged = {c: np.concatenate([p[c] for p in parts]) for c in COLUMNS}
    else:
        merged = {c: np.zeros(0) for c in COLUMNS}
    return PacketTable(merged, names, stats, truncs)


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
