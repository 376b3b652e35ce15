"""What both MAVLink endpoints share: the run's t0, the UDP peer, the fixed-rate clock, the log."""

from __future__ import annotations

import json
import select
import signal
import socket
import time
from collections import Counter
from pathlib import Path

from pymavlink.dialects.v20 import ardupilotmega

T0_WAIT_S = 300.0  # longest an endpoint started before t0 waits for it


def write_t0(path: Path, t0_unix: float) -> None:
    """Publish t0 to endpoints started before it (atomically: they poll for the file)."""
    tmp = path.with_suffix(".tmp")
    tmp.write_text(repr(t0_unix))
    tmp.replace(path)


def await_t0(spec, stop: "Stop") -> float:
    """The run's t0: given, or read from `t0_path` when the runner writes it. An endpoint is
    started before t0 (Python and pymavlink take seconds to load on a busy host) and says
    `ready` on stdout once it can send, so that at t0 it only has to read one small file."""
    if spec.t0_unix is not None:
        return spec.t0_unix
    if spec.t0_path is None:
        raise ValueError("the spec has neither t0_unix nor t0_path")
    print("ready", flush=True)
    end = time.time() + T0_WAIT_S
    while time.time() < end and not stop.flag:
        try:
            return float(spec.t0_path.read_text())
        except (FileNotFoundError, ValueError):
            time.sleep(0.002)
    raise TimeoutError("stopped before t0" if stop.flag else f"no t0 in {spec.t0_path} after {T0_WAIT_S:g} s")


class Stop:
    def __init__(self) -> None:
        self.flag = False
        signal.signal(signal.SIGTERM, self._set)

    def _set(self, *_):
        self.flag = True


class Peer:
    """One MAVLink link: pymavlink's packer/parser (own sequence numbers) bound to a UDP address."""

    def __init__(self, sock: socket.socket, addr, sysid: int, compid: int, sent: Counter) -> None:
        self.sock, self.addr, self.sent = sock, addr, sent
        # ardupilotmega: the ArduPilot messages (AHRS, MEMINFO, ...) on top of common, as both ends speak it
        self.mav = ardupilotmega.MAVLink(self, srcSystem=sysid, srcComponent=compid)
        self.mav.robust_parsing = True  # a bad frame becomes BAD_DATA (counted), not an exception

    def write(self, buf: bytes) -> None:  # pymavlink's `file`: one datagram per message
        try:
            self.sock.sendto(buf, self.addr)
        except OSError:
            pass  # no route this window: the radio's frame is lost, as it would be

    def send(self, msg) -> None:
        self.mav.send(msg)
        self.sent[msg.get_type()] += 1

    def send_to(self, msg, addr) -> None:
        """One message to another address than the peer's (an answer to whoever asked)."""
        home, self.addr = self.addr, addr
        try:
            self.send(msg)
        finally:
            self.addr = home

    def parse(self, data: bytes) -> list:
        return self.mav.parse_buffer(data) or []


class Log:
    def __init__(self, path: Path, t0_unix: float) -> None:
        path.parent.mkdir(parents=True, exist_ok=True)
        self.f, self.t0 = open(path, "a"), t0_unix

    def __call__(self, event: str, **kw) -> None:
        self.f.write(json.dumps({"t_s": round(time.time() - self.t0, 4), "event": event, **kw}) + "\n")
        self.f.flush()


def recv_all(sock: socket.socket, wait_s: float):
    """Datagrams that arrive within wait_s (all queued ones after the first)."""
    out = []
    r, _, _ = select.select([sock], [], [], max(0.0, wait_s))
    while r:
        try:
            out.append(sock.recvfrom(65535))
        except (BlockingIOError, ConnectionRefusedError):
            break
        r, _, _ = select.select([sock], [], [], 0)
    return out


class Periodic:
    """Due times of a fixed-rate message without drift (a late tick does not pile up)."""

    def __init__(self, rate_hz: float, now: float) -> None:
        self.period = 1.0 / rate_hz if rate_hz > 0 else None
        self.next = now

    def due(self, now: float) -> bool:
        if self.period is None or now < self.next:
            return False
        self.next += self.period
        if self.next < now:
            self.next = now + self.period
        return True



def read_log(path: Path) -> list[dict]:
    """The JSON lines of an endpoint's log (a torn last line, from a kill, is skipped)."""
    out = []
    for line in Path(path).read_text().splitlines():
        try:
            out.append(json.loads(line))
        except json.JSONDecodeError:
            continue
    return out
