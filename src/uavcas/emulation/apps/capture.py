"""One tcpdump per switch: every frame entering a switch is recorded once at that point.

tcpdump on the bridge device puts it in promiscuous mode, so the bridge passes every frame
received on any of its ports up to the capture (forwarded unicast included); hence no `-p`.
`-U` writes each packet as it comes (a crash loses nothing already seen), `-Z root` keeps the
file root-owned (tcpdump would otherwise drop privileges to the `tcpdump` user), `-B` gives the
kernel ring room for the flood bursts, `-n` avoids DNS. Frames a port mirror copies to an
attacker leave through tc on the port and never enter a bridge, so they are not captured twice.

Stopped with SIGINT, tcpdump flushes and prints its counters on stderr:
  "N packets captured / N packets received by filter / N packets dropped by kernel".
"""

from __future__ import annotations

import re
import signal
import time
from pathlib import Path

from uavcas.rundir import CaptureRecord

from .procs import Proc, spawn, wait_for

BUFFER_KIB = 8192
# libpcap's TPACKET_V3 ring hands a block to tcpdump when it is full or after the block timeout
# (tcpdump: 1000 ms); SIGINT discards a partly filled block. Traffic stops first, then we wait
# this long so the last block reaches the file.
DRAIN_S = 1.2
SNAPLEN = 262144


_STAT = re.compile(r"(\d+) packets? (captured|received by filter|dropped by kernel|dropped by interface)")


def parse_stats(stderr: str) -> dict[str, int]:
    out = {}
    for n, what in _STAT.findall(stderr):
        out[what] = int(n)
    return out


def point_name(node: str) -> str:
    """Capture point of node's switch, as docs/formats.md names it: s-uav3."""
    return f"s-{node}"


def argv(bridge: str, path: Path) -> list[str]:
    return ["tcpdump", "-i", bridge, "-n", "-U", "-Z", "root", "-B", str(BUFFER_KIB), "-s", str(SNAPLEN),
            "-w", str(path)]


class Capture:
    """tcpdump on one switch, started in the fabric namespace."""

    def __init__(self, emu, node: str, pcap_dir: Path, log_dir: Path, max_s: float) -> None:
        self.node, self.point = node, point_name(node)
        self.path = pcap_dir / f"{self.point}.pcap"
        self.bridge = emu.switch(node).bridge
        self.proc: Proc = spawn(emu.popen_fabric, f"tcpdump-{self.point}", argv(self.bridge, self.path),
                                log_dir, max_s)

    def ready(self) -> bool:
        return "listening on" in self.proc.stderr() or not self.proc.alive()

    def stop(self) -> CaptureRecord:
        code = self.proc.stop(signal.SIGINT, grace_s=5.0)
        wait_for(lambda: "captured" in self.proc.stderr(), 1.0)
        st = parse_stats(self.proc.stderr())
        size = self.path.stat().st_size if self.path.exists() else 0
        return CaptureRecord(point=self.point, path=str(self.path), captured=st.get("captured"),
                             received_by_filter=st.get("received by filter"),
                             dropped_by_kernel=st.get("dropped by kernel"),
                             dropped_by_interface=st.get("dropped by interface"), size_bytes=size, exit_code=code)


def stop_all(caps: list[Capture], drain_s: float = DRAIN_S) -> list[CaptureRecord]:
    time.sleep(drain_s)
    return [c.stop() for c in caps]


def start_all(emu, nodes: list[str], pcap_dir: Path, log_dir: Path, max_s: float,
              ready_timeout_s: float = 10.0) -> list[Capture]:
    pcap_dir.mkdir(parents=True, exist_ok=True)
    caps = [Capture(emu, n, pcap_dir, log_dir, max_s) for n in nodes]
    if not wait_for(lambda: all(c.ready() for c in caps), ready_timeout_s, 0.05):
        late = [c.point for c in caps if not c.ready()]
        raise RuntimeError(f"tcpdump did not start on {late[:5]}")
    dead = [f"{c.point}: {c.proc.stderr().strip()[-200:]}" for c in caps if not c.proc.alive()]
    if dead:
        raise RuntimeError(f"tcpdump exited early: {dead[0]}")
    return caps
