"""Seeded, JPEG-sized image payloads for the UAVs' web servers.

The flows we capture should look like a UAV serving camera frames: files of tens to hundreds of
KB with a log-normal size spread (compressed photos vary with scene content). The bytes are a
valid-looking JPEG envelope (SOI, APP0/JFIF, a quantisation table, SOF0, SOS, entropy-coded
noise, EOI) so payload-sniffing tools see image/jpeg; the "entropy" is random bytes, which is
what compressed data looks like on the wire. Same seed -> same files, byte for byte.
"""

from __future__ import annotations

import struct
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from uavcas import seeding

MEDIAN_KB = 120.0
SIGMA = 0.55  # log-normal shape: ~90 % of files between 50 and 300 KB
MIN_KB, MAX_KB = 20.0, 400.0
DEFAULT_COUNT = 24


@dataclass(frozen=True)
class Image:
    name: str
    size_bytes: int


def image_sizes(seed: int, count: int = DEFAULT_COUNT, median_kb: float = MEDIAN_KB,
                sigma: float = SIGMA) -> list[int]:
    rng = seeding.generator(seed, "image-sizes")
    kb = np.clip(rng.lognormal(np.log(median_kb), sigma, count), MIN_KB, MAX_KB)
    return [int(k * 1024) for k in kb]


def _segment(marker: int, payload: bytes) -> bytes:
    return struct.pack(">HH", marker, len(payload) + 2) + payload


def jpeg_bytes(size_bytes: int, rng: np.random.Generator, width: int = 1280, height: int = 720) -> bytes:
    head = b"\xff\xd8"
    head += _segment(0xFFE0, b"JFIF\x00\x01\x01\x00\x00\x48\x00\x48\x00\x00")
    head += _segment(0xFFDB, b"\x00" + bytes(rng.integers(1, 64, 64, dtype=np.uint8)))
    head += _segment(0xFFC0, struct.pack(">BHHB", 8, height, width, 3) + b"\x01\x22\x00\x02\x11\x01\x03\x11\x01")
    head += _segment(0xFFDA, b"\x03\x01\x00\x02\x11\x03\x11\x00\x3f\x00")
    body_len = max(0, size_bytes - len(head) - 2)
    body = bytearray(rng.bytes(body_len))
    # In entropy-coded data 0xFF is always stuffed with 0x00; avoid stray markers instead.
    body = body.replace(b"\xff", b"\xfe")
    return head + bytes(body) + b"\xff\xd9"


def generate(directory: Path, seed: int, count: int = DEFAULT_COUNT) -> list[Image]:
    """Write `count` images into `directory` (img000.jpg ...); returns their names and sizes."""
    directory.mkdir(parents=True, exist_ok=True)
    rng = seeding.generator(seed, "image-bytes")
    out = []
    for k, size in enumerate(image_sizes(seed, count)):
        name = f"img{k:03d}.jpg"
        (directory / name).write_bytes(jpeg_bytes(size, rng))
        out.append(Image(name, size))
    return out
