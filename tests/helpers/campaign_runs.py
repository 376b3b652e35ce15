"""Tiny real campaigns for the root campaign tests (tests/campaign): manifests, the CLI, services."""

from __future__ import annotations

import json
import socket
import subprocess
import sys
from pathlib import Path

import pyarrow.parquet as pq

from uavcas.scenario import ManifestEntry

TINY = (
    "benign-3-1-image-logdist-adaptive-random-30-95",
    "dos=1000-3-1-image-logdist-adaptive-spiral-30-95",
    "blackhole-3-1-image-logdist-adaptive-grid-30-95",
    "benign-3-1-image-logdist-adaptive-spiral-30-95",
)


def write_manifest(path: Path, n: int = 3, window_s: float = 4.0) -> list[ManifestEntry]:
    """The first `n` TINY scenarios, two windows each, written as a manifest file."""
    entries = [
        ManifestEntry(index=i, position=i, config=c, seed=100 + i, windows=2, window_s=window_s)
        for i, c in enumerate(TINY[:n])
    ]
    path.write_text("".join(json.dumps(e.to_dict()) + "\n" for e in entries))
    return entries


def cli(*args: str, **kw) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "uavcas.cli", *args], capture_output=True, text=True, **kw)


def services(ds: Path) -> dict[str, set]:
    cols = ["run_id", "src_ip", "dst_ip", "dst_port", "protocol", "label", "seq_flags"]
    t = pq.read_table(ds / "flows.parquet", columns=cols).to_pandas()
    # connections as opened (a TCP flow starting with a SYN, or any other protocol): the pieces a
    # FIN/RST cuts off (flows.assemble rule 4a) depend on retransmission timing, not on the service
    opening = [p != 6 or (len(f) > 0 and (int(f[0]) & 0x12) == 0x02) for p, f in zip(t.protocol, t.seq_flags)]
    t = t[opening]
    return {rid: set(map(tuple, g[["src_ip", "dst_ip", "dst_port", "protocol", "label"]].to_numpy().tolist()))
            for rid, g in t.groupby("run_id")}


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]
