"""Capture containers (pcap, pcapng) -> chunks of packet records, read a block at a time.

`iter_capture` reads the file in blocks of about `CHUNK_BYTES` and yields one `RawCapture` per
block: an index of the records that lie wholly inside it (a record cut by the block's end is
carried to the next block). Memory is therefore bounded by the block size, not the file size.
Only the record framing is walked in Python (one `unpack_from` per record, which is what bounds
the speed); protocol decoding is vectorised over a block's records in `uavcas.flows.decode`.

Timestamps are integer nanoseconds since the Unix epoch (`ts_ns`, int64): pcap's micro- or
nanosecond fractions and pcapng's `if_tsresol` ticks are converted exactly, so nothing is lost
to float64 (whose resolution at today's epoch is 238 ns).

A record that runs past the end of the file, or a block/record header that is implausible, is an
error naming the file and the byte offset; with `allow_truncated=True` reading stops there, the
records before it are kept and the offset is reported in `RawCapture.truncated_at`.
"""

from __future__ import annotations

import struct
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

import numpy as np

# Larger than any real snap length (tcpdump's maximum is 262144): anything above is corruption.
MAX_RECORD_BYTES = 16 * 1024 * 1024
# Bytes read per block: large enough that per-block numpy overheads vanish, small enough that
# the block, its decoded columns and the flows still open stay far below the memory budget.
CHUNK_BYTES = 32 * 1024 * 1024
NS = 1_000_000_000

PCAPNG_SHB = 0x0A0D0D0A
PCAPNG_IDB = 0x00000001
PCAPNG_PB = 0x00000002  # obsolete Packet Block
PCAPNG_SPB = 0x00000003
PCAPNG_EPB = 0x00000006
BYTE_ORDER_MAGIC = 0x1A2B3C4D
PCAP_MAGICS = (0xA1B2C3D4, 0xA1B23C4D, 0xD4C3B2A1, 0x4D3CB2A1)


class CaptureError(ValueError):
    """A capture file that cannot be read; the message names the file and the byte offset."""


@dataclass(frozen=True)
class RawCapture:
    """Record framing of one block of a capture file. Arrays have one entry per packet record."""

    path: str
    buf: np.ndarray  # uint8, the block's bytes (at least 64 bytes, zero padded if shorter)
    data_off: np.ndarray  # int64 offset of the first link-layer byte in buf
    cap_len: np.ndarray  # uint32 captured bytes
    wire_len: np.ndarray  # uint32 original length on the wire (tshark's frame.len)
    ts_ns: np.ndarray  # int64 Unix nanoseconds
    linktype: np.ndarray  # int32 LINKTYPE_* per record (pcapng interfaces may differ)
    first_record: int = 0  # record number (within the file) of this block's first record
    snaplen: int = 0  # the file's (smallest) snap length, 0 when unknown
    truncated_at: int | None = None  # byte offset where reading stopped early, if it did

    @property
    def n(self) -> int:
        return int(self.data_off.shape[0])


def iter_capture(path: str | Path, allow_truncated: bool = False,
                 chunk_bytes: int = CHUNK_BYTES) -> Iterator[RawCapture]:
    """Blocks of a pcap or pcapng file (format detected from the magic), in file order."""
    path = Path(path)
    try:
        fh = open(path, "rb")
    except OSError as exc:
        raise CaptureError(f"{path}: cannot read ({exc.strerror or exc})") from None
    with fh:
        head = fh.read(4)
        if len(head) < 4:
            raise CaptureError(f"{path}: not a pcap/pcapng file (only {len(head)} bytes) at byte offset 0")
        magic = struct.unpack("<I", head)[0]
        fh.seek(0)
        if magic == PCAPNG_SHB:
            yield from _iter_pcapng(path, fh, allow_truncated, chunk_bytes)
        elif magic in PCAP_MAGICS:
            yield from _iter_pcap(path, fh, allow_truncated, chunk_bytes)
        else:
            raise CaptureError(f"{path}: unknown capture magic 0x{magic:08x} at byte offset 0 (not pcap/pcapng)")


def _stop(path, allow: bool, offset: int, what: str) -> int:
    if not allow:
        raise CaptureError(
            f"{path}: {what} at byte offset {offset} (use --allow-truncated to keep the packets before it)"
        )
    return offset


def _as_buf(data: bytes) -> np.ndarray:
    if len(data) < 64:  # the vectorised gathers need a few bytes to clip into
        data = data + bytes(64 - len(data))
    return np.frombuffer(data, dtype=np.uint8)


class _Blocks:
    """Blocks of a file, each prefixed with the bytes the previous block left unconsumed."""

    def __init__(self, fh, chunk_bytes: int, base: int):
        self.fh, self.chunk_bytes, self.base = fh, chunk_bytes, base  # base: file offset of data[0]
        self.pending = b""

    def next(self) -> tuple[bytes, bool]:
        block = self.fh.read(self.chunk_bytes)
        self.data = self.pending + block if self.pending else block
        return self.data, len(block) < self.chunk_bytes

    def consumed(self, off: int) -> None:
        self.pending = self.data[off:]
        self.base += off


def _iter_pcap(path: Path, fh, allow: bool, chunk_bytes: int) -> Iterator[RawCapture]:
    head = fh.read(24)
    if len(head) < 24:
        raise CaptureError(f"{path}: truncated pcap global header at byte offset 0 ({len(head)} of 24 bytes)")
    magic = struct.unpack_from("<I", head, 0)[0]
    endian = "<" if magic in (0xA1B2C3D4, 0xA1B23C4D) else ">"
    frac_ns = 1 if magic in (0xA1B23C4D, 0x4D3CB2A1) else 1000
    snaplen = struct.unpack_from(endian + "I", head, 16)[0]
    linktype = struct.unpack_from(endian + "I", head, 20)[0] & 0x0FFFFFFF  # upper bits: FCS info
    unpack = struct.Struct(endian + "I").unpack_from
    blocks = _Blocks(fh, chunk_bytes, 24)
    record = 0
    while True:
        data, eof = blocks.next()
        base, n = blocks.base, len(data)
        offs: list[int] = []
        append = offs.append
        off = 0
        truncated_at = None
        # The hot loop only follows the chain of captured lengths (as lean as Python allows: it
        # is what bounds the reading speed); every other header field is then gathered for all
        # records of the block at once with numpy. It stops at the first record not wholly inside
        # the block, which the checks below tell apart: the next block's, truncated, or corrupt.
        lim = n - 16
        while off <= lim:
            end = off + 16 + unpack(data, off + 8)[0]
            if end > n:
                break
            append(off)
            off = end
        if off < n:
            incl = unpack(data, off + 8)[0] if off + 16 <= n else None
            if incl is not None and incl > MAX_RECORD_BYTES:
                truncated_at = _stop(path, allow, base + off, f"corrupt record header (captured length {incl})")
                eof = True
            elif eof and incl is None:
                truncated_at = _stop(path, allow, base + off, f"truncated record header ({n - off} of 16 bytes)")
            elif eof:
                truncated_at = _stop(path, allow, base + off,
                                     f"truncated packet record ({n - off - 16} of {incl} bytes)")
        hdr_at = np.asarray(offs, dtype=np.int64)
        raw = np.frombuffer(data, dtype=np.uint8)
        if offs:
            words = raw[hdr_at[:, None] + np.arange(16)].view(endian + "u4")
        else:
            words = np.zeros((0, 4), dtype=np.uint32)
        ts = words[:, 0].astype(np.int64) * NS + words[:, 1].astype(np.int64) * frac_ns
        yield RawCapture(
            path=str(path), buf=_as_buf(data), data_off=hdr_at + 16,
            cap_len=words[:, 2].astype(np.uint32), wire_len=words[:, 3].astype(np.uint32), ts_ns=ts,
            linktype=np.full(hdr_at.shape[0], linktype, dtype=np.int32), first_record=record,
            snaplen=int(snaplen), truncated_at=truncated_at,
        )  # fmt: skip
        record += len(offs)
        if eof or truncated_at is not None:
            return
        blocks.consumed(off)


def _tsresol_divisor(options: bytes, endian: str) -> int:
    """Ticks per second of a pcapng interface (option if_tsresol, code 9; default 10^6)."""
    i = 0
    while i + 4 <= len(options):
        code, length = struct.unpack_from(endian + "HH", options, i)
        if code == 0:
            break
        if code == 9 and length >= 1:
            v = options[i + 4]
            return 2 ** (v & 0x7F) if v & 0x80 else 10**v
        i += 4 + ((length + 3) & ~3)
    return 10**6


def ticks_to_ns(ticks: np.ndarray, div: np.ndarray) -> np.ndarray:
    """pcapng timestamps (ticks at `div` per second) -> int64 ns, exactly where the tick is >= 1 ns."""
    t = ticks.astype(np.uint64)
    d = np.maximum(div.astype(np.uint64), np.uint64(1))
    out = (t // d).astype(np.int64) * NS
    small = d <= NS  # remainder * 1e9 < 1e18 fits: exact integer arithmetic
    rem = t % d
    out[small] += ((rem[small] * np.uint64(NS)) // d[small]).astype(np.int64)
    if (~small).any():  # sub-nanosecond ticks: the remainder is below 1 s, float is exact to 1 ns
        out[~small] += (rem[~small].astype(np.float64) / d[~small].astype(np.float64) * NS).astype(np.int64)
    return out


def _iter_pcapng(path: Path, fh, allow: bool, chunk_bytes: int) -> Iterator[RawCapture]:
    ifaces: list[tuple[int, int, int]] = []  # (linktype, snaplen, ticks per second)
    endian = "<"
    blocks = _Blocks(fh, chunk_bytes, 0)
    record = 0
    while True:
        data, eof = blocks.next()
        base, n = blocks.base, len(data)
        offs: list[int] = []
        caps: list[int] = []
        wires: list[int] = []
        ticks: list[int] = []
        divs: list[int] = []
        links: list[int] = []
        off = 0
        truncated_at = None
        while off < n:
            if off + 12 > n:
                if eof:
                    truncated_at = _stop(path, allow, base + off, f"truncated pcapng block header ({n - off} bytes)")
                break
            btype = struct.unpack_from(endian + "I", data, off)[0]
            if btype == PCAPNG_SHB:  # a new section may switch byte order and resets interfaces
                bom = struct.unpack_from("<I", data, off + 8)[0]
                if bom == BYTE_ORDER_MAGIC:
                    endian = "<"
                elif bom == 0x4D3C2B1A:
                    endian = ">"
                else:
                    truncated_at = _stop(path, allow, base + off, f"corrupt pcapng section header (magic 0x{bom:08x})")
                    eof = True
                    break
                ifaces = []
            blen = struct.unpack_from(endian + "I", data, off + 4)[0]
            if blen < 12 or blen % 4 or blen > MAX_RECORD_BYTES:
                truncated_at = _stop(path, allow, base + off, f"corrupt pcapng block (length {blen})")
                eof = True
                break
            if off + blen > n:
                if eof:
                    truncated_at = _stop(path, allow, base + off, f"truncated pcapng block ({n - off} of {blen} bytes)")
                break
            body = off + 8
            if btype == PCAPNG_IDB:
                lt, _res, snap = struct.unpack_from(endian + "HHI", data, body)
                ifaces.append((lt, snap, _tsresol_divisor(data[body + 8 : off + blen - 4], endian)))
            elif btype == PCAPNG_EPB or btype == PCAPNG_PB:
                if btype == PCAPNG_EPB:
                    iface, hi, lo, incl, orig = struct.unpack_from(endian + "IIIII", data, body)
                else:
                    iface, _drops, hi, lo, incl, orig = struct.unpack_from(endian + "HHIIII", data, body)
                if iface >= len(ifaces) or body + 20 + incl > off + blen - 4:
                    truncated_at = _stop(path, allow, base + off, "corrupt pcapng packet block (interface/length)")
                    eof = True
                    break
                lt, _snap, div = ifaces[iface]
                offs.append(body + 20)
                caps.append(incl)
                wires.append(orig)
                ticks.append((hi << 32) | lo)
                divs.append(div)
                links.append(lt)
            elif btype == PCAPNG_SPB:
                if not ifaces:
                    truncated_at = _stop(path, allow, base + off, "pcapng simple packet block before any interface")
                    eof = True
                    break
                orig = struct.unpack_from(endian + "I", data, body)[0]
                lt, snap, div = ifaces[0]
                offs.append(body + 4)
                caps.append(min(orig, blen - 16, snap or orig))
                wires.append(orig)
                ticks.append(0)  # simple packet blocks carry no timestamp
                divs.append(div)
                links.append(lt)
            off += blen
        snaps = [s for _, s, _ in ifaces if s]
        yield RawCapture(
            path=str(path), buf=_as_buf(data),
            data_off=np.asarray(offs, dtype=np.int64), cap_len=np.asarray(caps, dtype=np.uint32),
            wire_len=np.asarray(wires, dtype=np.uint32),
            ts_ns=ticks_to_ns(np.asarray(ticks, dtype=np.uint64), np.asarray(divs, dtype=np.uint64)),
            linktype=np.asarray(links, dtype=np.int32), first_record=record,
            snaplen=min(snaps) if snaps else 0, truncated_at=truncated_at,
        )  # fmt: skip
        record += len(offs)
        if eof or truncated_at is not None:
            return
        blocks.consumed(off)
