"""A synthetic run directory for the fidelity audit: a known emulator, so known errors.

Three switches in a chain, uav0 - uav1 - bs0, two windows of 5 s. Packets uav0 -> bs0 are
"emulated" hop by hop with the FIFO model itself (uavcas.fidelity.fifo, checked by hand in
test_fifo.py) plus an error the test chooses per hop crossing, and dropped where the test says;
the captures are written as pcaps with microsecond stamps, like tcpdump's.
"""

from __future__ import annotations

import struct
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from uavcas.fidelity import fifo
from uavcas.network.forwarding import compute
from uavcas.rundir import ForwardingEpoch, RunDir, RunInfo
from uavcas.twin.model import Link, Node, Plan, Route, Window

T0 = 1_700_000_000.0
NAMES = ("uav0", "uav1", "bs0")
IPS = {"uav0": "10.20.0.1", "uav1": "10.20.0.2", "bs0": "10.20.1.1"}
PATH = ("uav0", "uav1", "bs0")


def link(a: str, b: str, rate_mbps: float, delay_ms: float, loss: float = 0.0) -> Link:
    return Link(a=a, b=b, kind="air", distance_m=80.0, pathloss_db=75.0, snr_db=22.0, mcs=4,
                rate_mbps=rate_mbps, delay_ms=delay_ms, loss=loss)


def plan(rate_mbps: float = 8.0, delay_ms: float = 2.0, loss_b: float = 0.0, loss_a: float = 0.0) -> Plan:
    """Both windows: uav0 - uav1 with loss `loss_a`, uav1 - bs0 with loss `loss_b`."""
    nodes = [Node(name=n, kind="bs" if n.startswith("bs") else "uav", index=i, ip=IPS[n],
                  mac=f"02:00:00:00:01:{i:02x}") for i, n in enumerate(NAMES)]
    wins = [Window(index=k, t_s=5.0 * k, duration_s=5.0, positions={},
                   links=[link("uav0", "uav1", rate_mbps, delay_ms, loss_a),
                          link("uav1", "bs0", rate_mbps, delay_ms, loss_b)],
                   routes=[Route(src="uav0", dst="bs0", hops=list(PATH))]) for k in range(2)]
    return Plan(config="test", seed=0, window_s=5.0, profile="test", area_m=(100.0, 100.0, 10.0, 50.0),
                nodes=nodes, windows=wins, attacks=[])


def run_info(**fields) -> RunInfo:
    base = dict(config="test", seed=0, windows=2, window_s=5.0, prefix="synth", t0_unix=T0, t_end_unix=T0 + 10,
                wall_s=11.0, exit_status=0, exit_reason="ok", versions={}, tool_versions={}, kernel="test",
                kernel_features=None, shaper_backend=None, timings={}, window_applies=[], schedule=[],
                capture=[], capture_drops=0, packets_captured=0, http_clients=[], delay_daemon=None,
                attack_errors=[], wind_down_errors=[])
    return RunInfo(**{**base, **fields})


def _ip(text: str) -> bytes:
    return bytes(int(x) for x in text.split("."))


def udp_frame(src: str, dst: str, sport: int, dport: int, ip_id: int, frame_len: int) -> bytes:
    """Ethernet + IPv4 + UDP, exactly `frame_len` bytes."""
    ip_len = frame_len - 14
    ip = struct.pack("!BBHHHBBH4s4s", 0x45, 0, ip_len, ip_id, 0, 64, 17, 0, _ip(src), _ip(dst))
    udp = struct.pack("!HHHH", sport, dport, ip_len - 20, 0)
    return b"\x02" * 6 + b"\x04" * 6 + b"\x08\x00" + ip + udp + b"\0" * (ip_len - 28)


def tcp_frame(src: str, dst: str, sport: int, dport: int, ip_id: int, frame_len: int) -> bytes:
    """Ethernet + IPv4 + TCP (an ACK, sequence number = IP id), exactly `frame_len` bytes."""
    ip_len = frame_len - 14
    ip = struct.pack("!BBHHHBBH4s4s", 0x45, 0, ip_len, ip_id, 0x4000, 64, 6, 0, _ip(src), _ip(dst))
    tcp = struct.pack("!HHIIBBHHH", sport, dport, ip_id, 1, 5 << 4, 0x10, 65535, 0, 0)
    return b"\x02" * 6 + b"\x04" * 6 + b"\x08\x00" + ip + tcp + b"\0" * (ip_len - 40)


def write_pcap(path: Path, frames: list[tuple[float, bytes]]) -> None:
    out = [struct.pack("<IHHiIII", 0xA1B2C3D4, 2, 4, 0, 0, 65535, 1)]
    for t, frame in sorted(frames, key=lambda x: x[0]):
        us = round(t * 1e6)
        out.append(struct.pack("<IIII", us // 1_000_000, us % 1_000_000, len(frame), len(frame)) + frame)
    path.write_bytes(b"".join(out))


@dataclass
class Traffic:
    """Packets sent at uav0's switch: time (s from T0), frame length, flow source port, IP id
    (None: the packet's index, so that every packet differs)."""

    t_s: list[float] = field(default_factory=list)
    length: list[int] = field(default_factory=list)
    sport: list[int] = field(default_factory=list)
    ip_id: list[int | None] = field(default_factory=list)

    def add(self, t_s: float, length: int = 1000, sport: int = 5000, ip_id: int | None = None) -> None:
        self.t_s.append(t_s)
        self.length.append(length)
        self.sport.append(sport)
        self.ip_id.append(ip_id)


# error(hop, packet index) -> seconds added to the model's arrival; drop(hop, index) -> lost there;
# stamp(position on PATH, packet index) -> seconds added to that capture's stamp alone
ErrorFn = Callable[[int, int], float]
DropFn = Callable[[int, int], bool]


def build(root: Path, p: Plan, traffic: Traffic, error: ErrorFn = lambda h, k: 0.0,
          drop: DropFn = lambda h, k: False, info: RunInfo | None = None,
          extra: dict[str, list[tuple[float, bytes]]] | None = None, stamp: ErrorFn = lambda h, k: 0.0,
          burst_b: float = fifo.HTB_BURST_BYTES, tcp: bool = False) -> RunDir:
    """Emulate `traffic` over PATH with the FIFO model + `error`, dropping what `drop` says;
    `extra`: more frames per node's capture (Unix s, bytes), written as given; `stamp`: a capture
    stamp off from when the frame was there (the emulation goes on from the true time); `burst_b`:
    the emulator's token-bucket depth; `tcp`: TCP segments instead of UDP datagrams."""
    rd = RunDir(root)
    rd.pcap_dir.mkdir(parents=True, exist_ok=True)
    rd.plan_json.write_text(p.to_json())
    rd.run_json.write_text((info or run_info()).to_json())
    names = [n.name for n in p.nodes]
    epochs = []
    for w in p.windows:
        fwd = compute(names, [(lk.a, lk.b) for lk in w.links], [r.hops for r in w.routes])
        epochs.append(ForwardingEpoch(t_begin_unix=T0 + w.t_s, t_unix=T0 + w.t_s, window=w.index,
                                      next_hop=fwd.next_hop))
    rd.forwarding_jsonl.write_text("".join(e.model_dump_json() + "\n" for e in epochs))
    n = len(traffic.t_s)
    length = np.array(traffic.length, dtype=float)
    t = T0 + np.array(traffic.t_s)
    alive = np.ones(n, dtype=bool)
    seen = {PATH[0]: (np.arange(n), t.copy())}
    for h, (a, b) in enumerate(zip(PATH, PATH[1:])):
        lk = next(lk for lk in p.windows[0].links if {lk.a, lk.b} == {a, b})
        idx = np.flatnonzero(alive)
        ready = t[idx] + lk.delay_ms / 1000
        order = np.argsort(ready, kind="stable")
        idx, ready = idx[order], ready[order]
        keep = np.array([not drop(h, int(k)) for k in idx], dtype=bool)
        # the port's rate by window, as the emulator rewrites it in place at each window's start
        rates = [next(x for x in w.links if {x.a, x.b} == {a, b}).rate_mbps for w in p.windows]
        start = fifo.serve(ready[keep], length[idx[keep]], T0 + np.array([w.t_s for w in p.windows]),
                           np.array(rates), burst_b)
        alive[idx[~keep]] = False
        got = idx[keep]
        t[got] = start + np.array([error(h, int(k)) for k in got])
        seen[b] = (got, t[got].copy())
    for node, (rows, times) in seen.items():
        times = times + np.array([stamp(PATH.index(node), int(k)) for k in rows])
        frames = [(float(tt), (tcp_frame if tcp else udp_frame)(IPS["uav0"], IPS["bs0"], traffic.sport[k], 9000,
                                        k % 65536 if traffic.ip_id[k] is None else traffic.ip_id[k],
                                        traffic.length[k])) for k, tt in zip(rows, times)]
        write_pcap(rd.pcap_dir / f"s-{node}.pcap", frames + (extra or {}).get(node, []))
    return rd
