"""Capture containers (pcap, pcapng) -> an index of packet records over one in-memory buffer.

Only the record framing is walked in Python (one `unpack_from` per record, which is what bounds
the speed); protocol decoding is vectorised over all records at once in `uavcas.flows.decode`.
A record that runs past the end of the file, or a block/record header that is implausible, is an
error naming the file and the byte offset; with `allow_truncated=True` reading stops there, the
records before it are kept and the offset is reported in `RawCapture.truncated_at`.
"""

from __future__ import annotations

import struct
from dataclasses import dataclass
from pathlib import Path

import numpy as np

# Larger than any real snap length (tcpdump's maximum is 262144): anything above is corruption.
MAX_RECORD_BYTES = 16 * 1024 * 1024
# Bytes of zero padding after the file so vectorised header reads never index past the buffer.
PAD_BYTES = 128

PCAPNG_SHB = 0x0A0D0D0A
PCAPNG_IDB = 0x00000001
PCAPNG_PB = 0x00000002  # obsolete Packet Block
PCAPNG_SPB = 0x00000003
PCAPNG_EPB = 0x00000006
BYTE_ORDER_MAGIC = 0x1A2B3C4D


class CaptureError(ValueError):
    """A capture file that cannot be read; the message names the file and the byte offset."""


@dataclass(frozen=True)
class RawCapture:
    """Record framing of one capture file. Arrays have one entry per packet record."""

    path: str
    buf: np.ndarray  # uint8, the whole file plus PAD_BYTES zeros
    data_off: np.ndarray  # int64 offset of the first link-layer byte in buf
    cap_len: np.ndarray  # uint32 captured bytes
    wire_len: np.ndarray  # uint32 original length on the wire (tshark's frame.len)
    ts_s: np.ndarray  # float64 Unix seconds
    linktype: np.ndarray  # int32 LINKTYPE_* per record (pcapng interfaces may differ)
    truncated_at: int | None = None  # byte offset where reading stopped early, if it did

    @property
    def n(self) -> int:
        return int(self.data_off.shape[0])


def read_capture(path: str | Path, allow_truncated: bool = False) -> RawCapture:
    """Index every packet record of a pcap or pcapng file (format detected from the magic)."""
    path = Path(path)
    try:
        data = path.read_bytes()
    except OSError as exc:
        raise CaptureError(f"{path}: cannot read ({exc.strerror or exc})") from None
    if len(data) < 4:
        raise CaptureError(f"{path}: not a pcap/pcapng file (only {len(data)} bytes) at byte offset 0")
    magic_le = struct.unpack_from("<I", data, 0)[0]
    if magic_le == PCAPNG_SHB:
        return _read_pcapng(path, data, allow_truncated)
    if magic_le in (0xA1B2C3D4, 0xA1B23C4D, 0xD4C3B2A1, 0x4D3CB2A1):
        return _read_pcap(path, data, allow_truncated)
    raise CaptureError(f"{path}: unknown capture magic 0x{magic_le:08x} at byte offset 0 (not pcap/pcapng)")


def _finish(path, data, offs, caps, wires, ts, links, truncated_at) -> RawCapture:
    buf = np.frombuffer(data + bytes(PAD_BYTES), dtype=np.uint8)
    return RawCapture(
        path=str(path),
        buf=buf,
        data_off=np.asarray(offs, dtype=np.int64),
        cap_len=np.asarray(caps, dtype=np.uint32),
        wire_len=np.asarray(wires, dtype=np.uint32),
        ts_s=np.asarray(ts, dtype=np.float64),
        linktype=np.asarray(links, dtype=np.int32),
        truncated_at=truncated_at,
    )


def _stop(path, allow: bool, offset: int, what: str) -> int:
    if not allow:
        raise CaptureError(
            f"{path}: {what} at byte offset {offset} (use --allow-truncated to keep the packets before it)"
        )
    return offset


def _read_pcap(path: Path, data: bytes, allow: bool) -> RawCapture:
    n = len(data)
    if n < 24:
        raise CaptureError(f"{path}: truncated pcap global header at byte offset 0 ({n} of 24 bytes)")
    magic = struct.unpack_from("<I", data, 0)[0]
    endian = "<" if magic in (0xA1B2C3D4, 0xA1B23C4D) else ">"
    nanos = magic in (0xA1B23C4D, 0x4D3CB2A1)
    linktype = struct.unpack_from(endian + "I", data, 20)[0] & 0x0FFFFFFF  # upper bits: FCS info
    unpack = struct.Struct(endian + "I").unpack_from
    offs: list[int] = []
    append = offs.append
    off = 24
    truncated_at = None
    # The hot loop only follows the chain of captured lengths; every other header field is then
    # gathered for all records at once with numpy.
    while off < n:
        if off + 16 > n:
            truncated_at = _stop(path, allow, off, f"truncated record header ({n - off} of 16 bytes)")
            break
        incl = unpack(data, off + 8)[0]
        if incl > MAX_RECORD_BYTES:
            truncated_at = _stop(path, allow, off, f"corrupt record header (captured length {incl})")
            break
        end = off + 16 + incl
        if end > n:
            truncated_at = _stop(
                path, allow, off, f"truncated packet record ({n - off - 16} of {incl} bytes)"
            )
            break
        append(off)
        off = end
    hdr_at = np.asarray(offs, dtype=np.int64)
    raw = np.frombuffer(data, dtype=np.uint8)
    words = raw[hdr_at[:, None] + np.arange(16)].view(endian + "u4") if offs else np.zeros((0, 4), dtype=np.uint32)
    secs, fracs, caps, wires = (words[:, k] for k in range(4))
    offs = hdr_at + 16
    ts = secs.astype(np.float64) + fracs.astype(np.float64) / (1e9 if nanos else 1e6)
    links = np.full(offs.shape[0], linktype, dtype=np.int32)
    return _finish(path, data, offs, caps, wires, ts, links, truncated_at)


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


def _read_pcapng(path: Path, data: bytes, allow: bool) -> RawCapture:
    n = len(data)
    offs: list[int] = []
    caps: list[int] = []
    wires: list[int] = []
    ticks: list[int] = []
    divs: list[int] = []
    links: list[int] = []
    ifaces: list[tuple[int, int, int]] = []  # (linktype, snaplen, ticks per second)
    endian = "<"
    off = 0
    truncated_at = None
    while off < n:
        if off + 12 > n:
            truncated_at = _stop(path, allow, off, f"truncated pcapng block header ({n - off} bytes)")
            break
        btype = struct.unpack_from(endian + "I", data, off)[0]
        if btype == PCAPNG_SHB:  # a new section may switch byte order and resets interfaces
            bom = struct.unpack_from("<I", data, off + 8)[0]
            if bom == BYTE_ORDER_MAGIC:
                endian = "<"
            elif bom == 0x4D3C2B1A:
                endian = ">"
            else:
                truncated_at = _stop(path, allow, off, f"corrupt pcapng section header (magic 0x{bom:08x})")
                break
            ifaces = []
        blen = struct.unpack_from(endian + "I", data, off + 4)[0]
        if blen < 12 or blen % 4 or blen > MAX_RECORD_BYTES:
            truncated_at = _stop(path, allow, off, f"corrupt pcapng block (length {blen})")
            break
        if off + blen > n:
            truncated_at = _stop(path, allow, off, f"truncated pcapng block ({n - off} of {blen} bytes)")
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
                truncated_at = _stop(path, allow, off, "corrupt pcapng packet block (interface/length)")
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
                truncated_at = _stop(path, allow, off, "pcapng simple packet block before any interface")
                break
            orig = struct.unpack_from(endian + "I", data, body)[0]
            lt, snap, div = ifaces[0]
            incl = min(orig, blen - 16, snap or orig)
            offs.append(body + 4)
            caps.append(incl)
            wires.append(orig)
            ticks.append(0)  # simple packet blocks carry no timestamp
            divs.append(div)
            links.append(lt)
        off += blen
    t = np.asarray(ticks, dtype=np.uint64)
    d = np.asarray(divs, dtype=np.uint64)
    # Split into whole seconds and a remainder so nanosecond ticks keep their precision.
    ts = (t // np.maximum(d, 1)).astype(np.float64) + (t % np.maximum(d, 1)).astype(np.float64) / d
    return _finish(path, data, offs, caps, wires, ts, links, truncated_at)
