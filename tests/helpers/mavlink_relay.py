"""The MAVLink endpoints (`uavcas.traffic.mavlink`) as processes on 127.0.0.1, with a UDP
relay between them that records every datagram both ways: shared by the endpoint, GPS-spoofing
and injection tests (tests/traffic, tests/emulation/apps)."""

from __future__ import annotations

import socket
import subprocess
import sys
import threading
import time

from uavcas.traffic import mavlink as mv


class Relay(threading.Thread):
    """UDP middle box: datagrams from the UAV go to the GCS and back; all of them are recorded."""

    def __init__(self, gcs_port: int, drop_once: tuple[str, ...] = ("MISSION_ITEM_INT", "COMMAND_LONG"),
                 drop_up=None) -> None:
        super().__init__(daemon=True)
        self.sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        self.sock.bind(("127.0.0.1", 0))
        self.sock.settimeout(0.1)
        self.port, self.gcs = self.sock.getsockname()[1], ("127.0.0.1", gcs_port)
        self.uav = None
        self.up: list[tuple[float, bytes]] = []  # UAV -> GCS
        self.down: list[tuple[float, bytes]] = []  # GCS -> UAV
        self.stop = False
        self.drop_once = set(drop_once)  # the first GCS -> UAV datagram of each type is lost
        self.drop_up = drop_up  # UAV -> GCS datagrams for which drop_up(data) is true are lost
        self.dropped_up: list[bytes] = []

    def run(self) -> None:
        while not self.stop:
            try:
                data, addr = self.sock.recvfrom(65535)
            except socket.timeout:
                continue
            if addr == self.gcs:
                self.down.append((time.time(), data))
                typ = type_of(data)
                if typ in self.drop_once:  # lost on the way: the GCS must retry it
                    self.drop_once.discard(typ)
                    continue
                if self.uav:
                    self.sock.sendto(data, self.uav)
            else:
                self.uav = addr
                self.up.append((time.time(), data))
                if self.drop_up is not None and self.drop_up(data):
                    self.dropped_up.append(data)
                    continue
                self.sock.sendto(data, self.gcs)


def bs0_uav0_specs(tmp_path, p, gcs_port: int, relay: Relay, dur: float) -> tuple:
    """The GCS of bs0 on `gcs_port` and uav0's autopilot talking to it through `relay`, for plan
    `p`, both stopping `dur` seconds after t0 and logging into `tmp_path`."""
    t0_path = tmp_path / "t0"
    gspec = mv.GcsSpec(name="bs0", sysid=p.node("bs0").sysid, bind_ip="127.0.0.1", port=gcs_port,
                       uavs=[mv.gcs_target(p, "uav0")], t0_path=t0_path, window_s=p.window_s,
                       n_windows=len(p.windows), duration_s=dur, log_path=tmp_path / "mavlink-bs0.jsonl")
    uspec = mv.uav_spec(p, "uav0", "127.0.0.1", None, dur, tmp_path / "mavlink-uav0.jsonl", gcs_port=relay.port,
                        bind_port=0, t0_path=t0_path)
    return gspec, uspec


def run_endpoints(tmp_path, gspec, uspec, relay: Relay, at_t0=lambda t0: None) -> float:
    """Both endpoints as processes until their deadline: they load, bind and say "ready" before t0
    (as in a run), then t0 is published and `at_t0(t0)` runs meanwhile. Returns t0."""
    (tmp_path / "g.json").write_text(gspec.model_dump_json())
    (tmp_path / "u.json").write_text(uspec.model_dump_json())
    run = [sys.executable, "-m", "uavcas.traffic.mavlink"]
    procs = [subprocess.Popen(run + [role, str(tmp_path / f"{role[0]}.json")], stdout=subprocess.PIPE,
                              stderr=subprocess.PIPE, text=True) for role in ("gcs", "uav")]
    try:
        assert [proc.stdout.readline().strip() for proc in procs] == ["ready", "ready"]
        t0 = time.time()
        mv.write_t0(uspec.t0_path, t0)
        at_t0(t0)
        wait_all(procs, uspec.duration_s + 10)
    finally:
        stop_all(relay, procs)
    return t0


def type_of(data: bytes) -> str:
    from pymavlink.dialects.v20 import ardupilotmega as common  # the dialect both endpoints speak

    return common.MAVLink(None).parse_buffer(data)[0].get_type()


def free_port() -> int:
    s = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    s.bind(("127.0.0.1", 0))
    port = s.getsockname()[1]
    s.close()
    return port


def wait_all(procs, timeout_s: float) -> None:
    """Every endpoint process ends by itself within timeout_s, with exit status 0."""
    for proc in procs:
        _, err = proc.communicate(timeout=timeout_s)
        assert proc.returncode == 0, err[-1000:]


def stop_all(relay: Relay, procs) -> None:
    relay.stop = True
    relay.join(2)
    for proc in procs:
        proc.kill()


def parse_each(datagrams):
    from pymavlink.dialects.v20 import ardupilotmega as common  # the dialect both endpoints speak

    out = []
    for t, d in datagrams:
        assert d[0] == 0xFD  # MAVLink 2 magic
        mav = common.MAVLink(None)  # strict: a bad CRC raises
        msgs = mav.parse_buffer(d)
        assert msgs is not None and len(msgs) == 1, d
        assert mav.total_receive_errors == 0 and msgs[0].get_type() != "BAD_DATA"
        out.append((t, msgs[0]))
    return out
