"""Optional MAVLink-like telemetry: each UAV sends small UDP datagrams to its BS at 10 Hz.

Off by default (the paper's traffic is the image transfer). The datagrams imitate MAVLink v2
framing (0xFD magic, length, sequence, system/component ids, message id, payload, CRC-sized
trailer) with HEARTBEAT, GLOBAL_POSITION_INT and ATTITUDE in rotation, so sizes and cadence
look like a flight controller's stream. The BS runs a sink so no ICMP port-unreachable noise
appears. Both ends are bounded by their own deadline and the core's `timeout`.

Run: python -m uavcas.emulation.apps.telemetry send --dst IP --sysid N --hz 10 --seconds S
     python -m uavcas.emulation.apps.telemetry sink --seconds S
"""

from __future__ import annotations

import argparse
import os
import socket
import struct
import time

PORT = 14550
HZ = 10.0
MESSAGES = ((0, 9), (33, 28), (30, 28))  # (msgid, payload length): HEARTBEAT, GLOBAL_POSITION_INT, ATTITUDE


def frame(seq: int, sysid: int, msgid: int, payload_len: int) -> bytes:
    header = struct.pack("<BBBBBBBH", 0xFD, payload_len, 0, 0, seq & 0xFF, sysid & 0xFF, 1, msgid & 0xFFFF)
    header += bytes([(msgid >> 16) & 0xFF])
    return header + os.urandom(payload_len) + os.urandom(2)  # payload, CRC-sized trailer


def send(dst: str, sysid: int, hz: float, seconds: float, port: int = PORT) -> int:
    s = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    start = time.monotonic()
    n = 0
    while (now := time.monotonic()) < start + seconds:
        msgid, plen = MESSAGES[n % len(MESSAGES)]
        try:
            s.sendto(frame(n, sysid, msgid, plen), (dst, port))
        except OSError:
            pass  # link down this window: a radio would lose it too
        n += 1
        time.sleep(max(0.0, start + n / hz - time.monotonic()))
    return n


def sink(seconds: float, port: int = PORT) -> int:
    s = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    s.bind(("0.0.0.0", port))
    end = time.monotonic() + seconds
    n = 0
    while (left := end - time.monotonic()) > 0:
        s.settimeout(left)
        try:
            s.recv(2048)
            n += 1
        except socket.timeout:
            break
    return n


def main() -> None:
    ap = argparse.ArgumentParser()
    sub = ap.add_subparsers(dest="cmd", required=True)
    a = sub.add_parser("send")
    a.add_argument("--dst", required=True)
    a.add_argument("--sysid", type=int, default=1)
    a.add_argument("--hz", type=float, default=HZ)
    a.add_argument("--seconds", type=float, required=True)
    b = sub.add_parser("sink")
    b.add_argument("--seconds", type=float, required=True)
    args = ap.parse_args()
    if args.cmd == "send":
        print(send(args.dst, args.sysid, args.hz, args.seconds), flush=True)
    else:
        print(sink(args.seconds), flush=True)


if __name__ == "__main__":
    main()
