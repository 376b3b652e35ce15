"""MAVLink v2 between every UAV's autopilot and its base station's ground station (pymavlink).

Two endpoint processes, one per node, each a small MAVLink peer over UDP (one message per
datagram; every byte is packed and parsed by pymavlink's `dialects.v20.common`):

* `uav` (autopilot, in the UAV's namespace): HEARTBEAT at 1 Hz (MAV_TYPE_QUADROTOR,
  MAV_AUTOPILOT_ARDUPILOTMEGA, Copter custom mode AUTO = 3) to its BS's port 14550, always, also
  while the plan marks it disconnected (a radio sends into the void). The streams start at
  ArduCopter's defaults, which are 0 Hz (libraries/GCS_MAVLink/GCS_MAVLink_Parameters.cpp:
  AP_MAV_DEFAULT_STREAM_RATE_EXT_STAT, _POSITION, _EXTRA1, _EXTRA2 = 0 for
  APM_BUILD_COPTER_OR_HELI, i.e. MAVn_EXT_STAT/_POSITION/_EXTRA1/_EXTRA2, formerly
  SRn_*, default 0): a Copter streams what a GCS asks for with REQUEST_DATA_STREAM, per
  ArduPilot's group: EXTENDED_STATUS = SYS_STATUS + GPS_RAW_INT, POSITION =
  GLOBAL_POSITION_INT, EXTRA1 = ATTITUDE, EXTRA2 = VFR_HUD. Values come from the plan's track
  (`uavcas.twin.track`): position, velocity, heading, ground speed; ATTITUDE has yaw = heading
  and roll = pitch = 0 (the track's velocity is constant within a window: no acceleration to
  tilt for); GPS_RAW_INT has fix type 3 (3D) and 12 satellites; the battery drains linearly
  (`BatterySpec`). It accepts a mission (MISSION_COUNT -> MISSION_REQUEST_INT per item ->
  MISSION_ACK) and acknowledges COMMAND_LONG with COMMAND_ACK (MAV_RESULT_ACCEPTED).
* `gcs` (ground station, in the BS's namespace, UDP 14550, all its UAVs): from the first
  datagram of a UAV on, HEARTBEAT (MAV_TYPE_GCS) at 1 Hz to it, REQUEST_DATA_STREAM at
  `StreamRates` (default: MAVProxy's `streamrate` setting, 4 Hz, with which it asks an
  ArduPilot vehicle for every stream; heartbeat 1 Hz, its `heartbeat` setting), the mission
  upload (the UAV's window-start positions as MAV_CMD_NAV_WAYPOINT items, relative altitude),
  and at every window boundary COMMAND_LONG MAV_CMD_DO_CHANGE_SPEED with the UAV's planned
  ground speed over the new window.

Retries: mission messages and commands are resent after `RetrySpec.timeout_s` (0.5 s, MAVSDK's
default MAVLink timeout), at most `mission_retries` / `command_retries` times (the command's
`confirmation` counts the resends, as the command protocol asks). Times are plan times from the
run's t0 (time_boot_ms = ms since t0), which an endpoint started before t0 reads from a file
the runner writes at t0 (`write_t0`). Both ends stop at their deadline or on SIGTERM and
log JSON lines to `log_path`: one line per mission upload, command and ack as they happen, and a
final `summary` line with sent/received message counts per type.

Run: python -m uavcas.emulation.apps.mavlink {uav|gcs} SPEC.json
"""

from __future__ import annotations

import argparse
import json
import math
import select
import signal
import socket
import sys
import time
from collections import Counter
from pathlib import Path
from typing import Literal

from pydantic import BaseModel, ConfigDict, Field

from uavcas.twin.model import Site
from uavcas.twin.track import Track, local_to_geodetic

GCS_PORT = 14550  # the customary ground-station UDP port (MAVProxy, QGroundControl, Mission Planner)
COMPONENT_AUTOPILOT = 1  # MAV_COMP_ID_AUTOPILOT1
COMPONENT_GCS = 190  # MAV_COMP_ID_MISSIONPLANNER, what ground stations use
COPTER_MODE_AUTO = 3  # ArduCopter custom_mode AUTO: flying the uploaded mission
GPS_FIX_3D = 3
GPS_SATELLITES = 12


def _mavlink():
    # imported on use: pymavlink builds its message classes at import (~0.2 s)
    from pymavlink.dialects.v20 import common

    return common


class _Frozen(BaseModel):
    model_config = ConfigDict(frozen=True, extra="forbid")


class StreamRates(_Frozen):
    """What the GCS requests (Hz, REQUEST_DATA_STREAM's integer rates; ArduPilot allows 0-50).

    Default: MAVProxy's `streamrate` 4 (mavproxy.py MPSettings), which it requests for all
    streams; heartbeat 1 Hz (MAVProxy `heartbeat`; ArduPilot sends its own at 1 Hz too).
    """

    heartbeat_rate_hz: float = Field(default=1.0, gt=0, le=50)
    ext_stat_rate_hz: int = Field(default=4, ge=0, le=50)  # SYS_STATUS, GPS_RAW_INT
    position_rate_hz: int = Field(default=4, ge=0, le=50)  # GLOBAL_POSITION_INT
    extra1_rate_hz: int = Field(default=4, ge=0, le=50)  # ATTITUDE
    extra2_rate_hz: int = Field(default=4, ge=0, le=50)  # VFR_HUD

    def requests(self) -> list[tuple[int, int]]:
        """(MAV_DATA_STREAM id, rate Hz) pairs the GCS sends."""
        m = _mavlink()
        return [(m.MAV_DATA_STREAM_EXTENDED_STATUS, self.ext_stat_rate_hz),
                (m.MAV_DATA_STREAM_POSITION, self.position_rate_hz),
                (m.MAV_DATA_STREAM_EXTRA1, self.extra1_rate_hz),
                (m.MAV_DATA_STREAM_EXTRA2, self.extra2_rate_hz)]

    def expected_hz(self) -> dict[str, float]:
        """Message type -> rate the UAV sends it at once the request is granted."""
        return {"HEARTBEAT": self.heartbeat_rate_hz, "SYS_STATUS": self.ext_stat_rate_hz,
                "GPS_RAW_INT": self.ext_stat_rate_hz, "GLOBAL_POSITION_INT": self.position_rate_hz,
                "ATTITUDE": self.extra1_rate_hz, "VFR_HUD": self.extra2_rate_hz}


# ArduPilot's stream groups of the messages we send (GCS_MAVLink_Parameters.cpp STREAM_*_msgs)
STREAM_MESSAGES = {2: ("SYS_STATUS", "GPS_RAW_INT"), 6: ("GLOBAL_POSITION_INT",), 10: ("ATTITUDE",),
                   11: ("VFR_HUD",)}  # MAV_DATA_STREAM_EXTENDED_STATUS, _POSITION, _EXTRA1, _EXTRA2


class BatterySpec(_Frozen):
    """A constant-current discharge: remaining = 1 - current * t / capacity, the voltage linear in
    the remaining charge from full to empty (a 4S LiPo: 4.2 V to 3.5 V per cell)."""

    capacity_mah: float = Field(default=5000.0, gt=0)
    current_a: float = Field(default=20.0, ge=0)  # a ~2 kg quadrotor's hover draw: 15 min on 5 Ah
    full_v: float = 16.8
    empty_v: float = 14.0

    def at(self, t_s: float) -> tuple[int, int, int]:
        """(voltage mV, current cA, remaining %) at plan time t."""
        used = self.current_a * max(t_s, 0.0) / 3600.0 * 1000.0 / self.capacity_mah
        remaining = min(1.0, max(0.0, 1.0 - used))
        volts = self.empty_v + (self.full_v - self.empty_v) * remaining
        return round(volts * 1000), round(self.current_a * 100), round(remaining * 100)


class RetrySpec(_Frozen):
    timeout_s: float = Field(default=0.5, gt=0)  # MAVSDK's default MAVLink transfer timeout
    mission_retries: int = Field(default=5, ge=0)
    command_retries: int = Field(default=3, ge=0)


class UavSpec(_Frozen):
    kind: Literal["uav"] = "uav"
    name: str
    sysid: int = Field(ge=1, le=255)
    gcs_ip: str
    gcs_port: int = GCS_PORT
    bind_ip: str = "0.0.0.0"
    site: Site
    times_s: list[float]  # the plan's track: window starts ...
    positions_m: list[tuple[float, float, float]]  # ... and the UAV's position at each
    t0_unix: float | None = None  # plan t = 0; None: read from t0_path once it appears
    t0_path: Path | None = None
    duration_s: float
    battery: BatterySpec = BatterySpec()
    retry: RetrySpec = RetrySpec()
    log_path: Path

    def track(self) -> Track:
        return Track(tuple(self.times_s), tuple(tuple(p) for p in self.positions_m))


class GcsTarget(_Frozen):
    name: str
    sysid: int = Field(ge=1, le=255)
    waypoints: list[tuple[float, float, float]]  # lat deg, lon deg, metres above the site
    speeds_mps: list[float]  # planned ground speed in each window


class GcsSpec(_Frozen):
    kind: Literal["gcs"] = "gcs"
    name: str
    sysid: int = Field(ge=1, le=255)
    bind_ip: str = "0.0.0.0"
    port: int = GCS_PORT
    rates: StreamRates = StreamRates()
    retry: RetrySpec = RetrySpec()
    uavs: list[GcsTarget]
    t0_unix: float | None = None  # as UavSpec
    t0_path: Path | None = None
    window_s: float = Field(gt=0)
    n_windows: int = Field(ge=1)
    duration_s: float
    log_path: Path


def gcs_target(plan, uav: str) -> GcsTarget:
    """What a GCS knows of a UAV it serves: its waypoints and per-window speeds, from the plan."""
    node = plan.node(uav)
    if node.sysid is None:
        raise ValueError(f"{uav} has no MAVLink system id in the plan")
    track = Track.of(plan, uav)
    wps = [local_to_geodetic(plan.site, *p) for p in track.positions_m]
    return GcsTarget(name=uav, sysid=node.sysid,
                     waypoints=[(lat, lon, alt - plan.site.alt_m) for lat, lon, alt in wps],
                     speeds_mps=[track.speed_in_window_mps(k) for k in range(len(plan.windows))])


def uav_spec(plan, uav: str, gcs_ip: str, t0_unix: float | None, duration_s: float, log_path: Path,
             **kw) -> UavSpec:
    node = plan.node(uav)
    if node.sysid is None:
        raise ValueError(f"{uav} has no MAVLink system id in the plan")
    track = Track.of(plan, uav)
    return UavSpec(name=uav, sysid=node.sysid, gcs_ip=gcs_ip, site=plan.site, times_s=list(track.times_s),
                   positions_m=list(track.positions_m), t0_unix=t0_unix, duration_s=duration_s,
                   log_path=log_path, **kw)


# --- the endpoints -------------------------------------------------------------------------------
T0_WAIT_S = 300.0  # longest an endpoint started before t0 waits for it


def write_t0(path: Path, t0_unix: float) -> None:
    """Publish t0 to endpoints started before it (atomically: they poll for the file)."""
    tmp = path.with_suffix(".tmp")
    tmp.write_text(repr(t0_unix))
    tmp.replace(path)


def _await_t0(spec, stop: "_Stop") -> float:
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


class _Stop:
    def __init__(self) -> None:
        self.flag = False
        signal.signal(signal.SIGTERM, self._set)

    def _set(self, *_):
        self.flag = True


class _Peer:
    """One MAVLink link: pymavlink's packer/parser (own sequence numbers) bound to a UDP address."""

    def __init__(self, sock: socket.socket, addr, sysid: int, compid: int, sent: Counter) -> None:
        self.sock, self.addr, self.sent = sock, addr, sent
        self.mav = _mavlink().MAVLink(self, srcSystem=sysid, srcComponent=compid)
        self.mav.robust_parsing = True  # a bad frame becomes BAD_DATA (counted), not an exception

    def write(self, buf: bytes) -> None:  # pymavlink's `file`: one datagram per message
        try:
            self.sock.sendto(buf, self.addr)
        except OSError:
            pass  # no route this window: the radio's frame is lost, as it would be

    def send(self, msg) -> None:
        self.mav.send(msg)
        self.sent[msg.get_type()] += 1

    def parse(self, data: bytes) -> list:
        return self.mav.parse_buffer(data) or []


class _Log:
    def __init__(self, path: Path, t0_unix: float) -> None:
        path.parent.mkdir(parents=True, exist_ok=True)
        self.f, self.t0 = open(path, "a"), t0_unix

    def __call__(self, event: str, **kw) -> None:
        self.f.write(json.dumps({"t_s": round(time.time() - self.t0, 4), "event": event, **kw}) + "\n")
        self.f.flush()


def _recv_all(sock: socket.socket, wait_s: float):
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


class _Periodic:
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


def run_uav(spec: UavSpec) -> dict:
    m = _mavlink()
    stop = _Stop()
    sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    sock.bind((spec.bind_ip, 0))
    sock.setblocking(False)
    sent, received = Counter(), Counter()
    gcs = _Peer(sock, (spec.gcs_ip, spec.gcs_port), spec.sysid, COMPONENT_AUTOPILOT, sent)
    track = spec.track()
    spec = spec.model_copy(update={"t0_unix": _await_t0(spec, stop)})
    log = _Log(spec.log_path, spec.t0_unix)
    deadline = spec.t0_unix + spec.duration_s
    now = time.time()
    heartbeat = _Periodic(1.0, now)
    streams = {sid: _Periodic(0.0, now) for sid in STREAM_MESSAGES}  # ArduCopter default: 0 Hz
    mission: dict = {"count": None, "items": {}, "from_": None, "asked": None, "seq": None, "tries": 0}
    speed_mps: float | None = None
    while not stop.flag and (now := time.time()) < deadline:
        for data, addr in _recv_all(sock, _wait(now, deadline, heartbeat, streams, mission, spec.retry.timeout_s)):
            for msg in gcs.parse(data):
                typ = msg.get_type()
                received[typ] += 1
                if typ == "BAD_DATA" or msg.get_srcSystem() == spec.sysid:
                    continue
                gcs.addr = addr  # answer where the GCS speaks from
                if typ == "REQUEST_DATA_STREAM" and msg.target_system == spec.sysid:
                    ids = STREAM_MESSAGES if msg.req_stream_id == m.MAV_DATA_STREAM_ALL else [msg.req_stream_id]
                    for sid in ids:
                        if sid in streams:
                            rate = msg.req_message_rate if msg.start_stop else 0
                            streams[sid] = _Periodic(float(rate), time.time())
                elif typ == "MISSION_COUNT" and msg.target_system == spec.sysid:
                    mission.update(count=msg.count, items={}, from_=(msg.get_srcSystem(), msg.get_srcComponent()),
                                   asked=None, tries=0)
                    log("mission_count", count=msg.count)
                    _ask_next(gcs, m, mission, spec, log)
                elif (typ == "MISSION_ITEM_INT" and msg.target_system == spec.sysid and mission["count"]
                      and mission["asked"] is not None and msg.seq == mission["seq"]):
                    # only the item asked for: a duplicate (both ends retried) must not ask again
                    mission["items"][msg.seq] = (msg.x / 1e7, msg.y / 1e7, msg.z)
                    _ask_next(gcs, m, mission, spec, log)
                elif typ == "COMMAND_LONG" and msg.target_system == spec.sysid:
                    result = m.MAV_RESULT_UNSUPPORTED
                    if msg.command == m.MAV_CMD_DO_CHANGE_SPEED:
                        speed_mps, result = float(msg.param2), m.MAV_RESULT_ACCEPTED
                    gcs.send(m.MAVLink_command_ack_message(msg.command, result, 0, 0, msg.get_srcSystem(),
                                                           msg.get_srcComponent()))
                    log("command", command=int(msg.command), confirmation=int(msg.confirmation),
                        param2=float(msg.param2), result=int(result))
        now = time.time()
        t = now - spec.t0_unix
        if mission["asked"] is not None and now >= mission["asked"] + spec.retry.timeout_s:
            if mission["tries"] >= spec.retry.mission_retries:
                log("mission_receive", result="timeout", items=len(mission["items"]), count=mission["count"])
                mission.update(count=None, asked=None)
            else:
                mission["tries"] += 1
                _ask_next(gcs, m, mission, spec, log, resend=True)
        p = track.at(t)
        if heartbeat.due(now):
            gcs.send(m.MAVLink_heartbeat_message(
                m.MAV_TYPE_QUADROTOR, m.MAV_AUTOPILOT_ARDUPILOTMEGA,
                m.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED | m.MAV_MODE_FLAG_SAFETY_ARMED | m.MAV_MODE_FLAG_STABILIZE_ENABLED
                | m.MAV_MODE_FLAG_GUIDED_ENABLED | m.MAV_MODE_FLAG_AUTO_ENABLED,
                COPTER_MODE_AUTO, m.MAV_STATE_ACTIVE, 3))
        for sid, per in streams.items():
            if per.due(now):
                for typ in STREAM_MESSAGES[sid]:
                    gcs.send(_telemetry(m, typ, spec, p, t))
    summary = {"node": spec.name, "sysid": spec.sysid, "sent": dict(sent), "received": dict(received),
               "mission_items": len(mission["items"]), "last_speed_mps": speed_mps}
    log("summary", **summary)
    return summary


def _wait(now, deadline, heartbeat, streams, mission, timeout_s: float) -> float:
    """Seconds until the UAV's next own action: a message due, a mission retry, the deadline."""
    nxt = [deadline, heartbeat.next] + [p.next for p in streams.values() if p.period is not None]
    if mission["asked"] is not None:
        nxt.append(mission["asked"] + timeout_s)
    return max(0.0, min(nxt) - now)


def _ask_next(gcs: _Peer, m, mission: dict, spec: UavSpec, log, resend: bool = False) -> None:
    """Request the lowest missing item, or acknowledge the complete mission."""
    missing = [k for k in range(mission["count"]) if k not in mission["items"]]
    sysid, compid = mission.get("from_") or (0, 0)
    if not missing:
        gcs.send(m.MAVLink_mission_ack_message(sysid, compid, m.MAV_MISSION_ACCEPTED, m.MAV_MISSION_TYPE_MISSION))
        log("mission_receive", result="accepted", items=len(mission["items"]), count=mission["count"])
        mission.update(asked=None)
        return
    if not resend:
        mission["tries"] = 0
    gcs.send(m.MAVLink_mission_request_int_message(sysid, compid, missing[0], m.MAV_MISSION_TYPE_MISSION))
    mission["asked"], mission["seq"] = time.time(), missing[0]


def _telemetry(m, typ: str, spec: UavSpec, p, t: float):
    lat, lon, alt = local_to_geodetic(spec.site, p.x_m, p.y_m, p.z_m)
    boot_ms = max(0, round(t * 1000)) & 0xFFFFFFFF
    gs = p.groundspeed_mps
    if typ == "GLOBAL_POSITION_INT":  # velocities NED, cm/s
        return m.MAVLink_global_position_int_message(
            boot_ms, round(lat * 1e7), round(lon * 1e7), round(alt * 1000), round(p.z_m * 1000),
            round(p.vy_mps * 100), round(p.vx_mps * 100), round(-p.vz_mps * 100), round(p.heading_deg * 100) % 36000)
    if typ == "GPS_RAW_INT":
        return m.MAVLink_gps_raw_int_message(
            boot_ms * 1000, GPS_FIX_3D, round(lat * 1e7), round(lon * 1e7), round(alt * 1000), 100, 100,
            round(gs * 100), round(p.heading_deg * 100) % 36000, GPS_SATELLITES)
    if typ == "ATTITUDE":
        yaw = math.radians(p.heading_deg)
        return m.MAVLink_attitude_message(boot_ms, 0.0, 0.0, math.atan2(math.sin(yaw), math.cos(yaw)), 0.0, 0.0, 0.0)
    if typ == "VFR_HUD":  # no wind: airspeed = ground speed
        return m.MAVLink_vfr_hud_message(gs, gs, round(p.heading_deg) % 360, 50, alt, p.vz_mps)
    if typ == "SYS_STATUS":
        mv, ca, pct = spec.battery.at(t)
        sensors = (m.MAV_SYS_STATUS_SENSOR_3D_GYRO | m.MAV_SYS_STATUS_SENSOR_3D_ACCEL | m.MAV_SYS_STATUS_SENSOR_GPS
                   | m.MAV_SYS_STATUS_SENSOR_ABSOLUTE_PRESSURE | m.MAV_SYS_STATUS_SENSOR_BATTERY)
        return m.MAVLink_sys_status_message(sensors, sensors, sensors, 250, mv, ca, pct, 0, 0, 0, 0, 0, 0)
    raise ValueError(f"no telemetry message {typ!r}")


def run_gcs(spec: GcsSpec) -> dict:
    m = _mavlink()
    stop = _Stop()
    sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
    sock.bind((spec.bind_ip, spec.port))
    sock.setblocking(False)
    spec = spec.model_copy(update={"t0_unix": _await_t0(spec, stop)})
    log = _Log(spec.log_path, spec.t0_unix)
    log("listening", port=spec.port, uavs=[u.name for u in spec.uavs])
    sent, received = Counter(), Counter()
    targets = {u.sysid: u for u in spec.uavs}
    received_by: dict[str, Counter] = {u.name: Counter() for u in spec.uavs}
    peers: dict[int, _Peer] = {}
    state: dict[int, dict] = {}
    deadline = spec.t0_unix + spec.duration_s
    stream_wait_s = 2.0  # re-request streams not seen this long after a request (bounded retries)
    while not stop.flag and (now := time.time()) < deadline:
        waits = [deadline]
        for sysid, st in state.items():
            waits += [st["hb"].next, st["pending_at"] + spec.retry.timeout_s if st["pending"] else deadline,
                      st["cmd_at"] + spec.retry.timeout_s if st["cmd"] else deadline]
        for k in range(1, spec.n_windows):
            if spec.t0_unix + k * spec.window_s > now:
                waits.append(spec.t0_unix + k * spec.window_s)
                break
        for data, addr in _recv_all(sock, max(0.0, min(waits) - now)):
            probe = m.MAVLink(None)  # one message per datagram: a fresh parser per datagram
            probe.robust_parsing = True
            for msg in probe.parse_buffer(data) or []:
                typ, src = msg.get_type(), msg.get_srcSystem()
                received[typ] += 1
                if typ == "BAD_DATA" or src not in targets:
                    continue
                received_by[targets[src].name][typ] += 1
                if src not in peers:
                    peers[src] = _Peer(sock, addr, spec.sysid, COMPONENT_GCS, sent)
                    state[src] = {"hb": _Periodic(spec.rates.heartbeat_rate_hz, time.time()), "pending": None,
                                  "pending_at": 0.0, "tries": 0, "mission_t0": time.time() - spec.t0_unix,
                                  "uploaded": False, "cmd": None, "cmd_at": 0.0, "cmd_tries": 0,
                                  "streams_at": None, "stream_tries": 0, "streaming": False,
                                  "window": max(0, int((time.time() - spec.t0_unix) // spec.window_s))}
                    log("heard", uav=targets[src].name, sysid=src)
                    _request_streams(peers[src], m, spec, src, state[src])
                    _mission_start(peers[src], m, targets[src], state[src])
                peers[src].addr = addr
                _gcs_handle(m, msg, typ, peers[src], targets[src], state[src], spec, log)
        now = time.time()
        # window boundaries: the planned speed of the new window to every UAV heard
        k = int((now - spec.t0_unix) // spec.window_s)
        for src, st in state.items():
            if 1 <= k < spec.n_windows and st["window"] < k:
                st["window"] = k
                if st["cmd"] is not None:
                    log("command_result", uav=targets[src].name, window=st["cmd"]["window"], result="superseded")
                st["cmd"], st["cmd_tries"] = {"window": k, "speed": targets[src].speeds_mps[k]}, 0
                _send_command(peers[src], m, src, st)
                log("command_sent", uav=targets[src].name, window=k, speed_mps=round(st["cmd"]["speed"], 4))
        for src, st in state.items():
            peer, tgt = peers[src], targets[src]
            if st["hb"].due(now):
                peer.send(m.MAVLink_heartbeat_message(m.MAV_TYPE_GCS, m.MAV_AUTOPILOT_INVALID, 0, 0,
                                                      m.MAV_STATE_ACTIVE, 3))
            if st["pending"] and now >= st["pending_at"] + spec.retry.timeout_s:
                if st["tries"] >= spec.retry.mission_retries:
                    log("mission_upload", uav=tgt.name, result="timeout", t_s=round(now - spec.t0_unix, 4))
                    st["pending"] = None
                else:
                    st["tries"] += 1
                    _resend_mission(peer, m, tgt, st)
            if st["cmd"] and now >= st["cmd_at"] + spec.retry.timeout_s:
                if st["cmd_tries"] >= spec.retry.command_retries:
                    log("command_result", uav=tgt.name, window=st["cmd"]["window"], result="timeout")
                    st["cmd"] = None
                else:
                    st["cmd_tries"] += 1
                    _send_command(peer, m, src, st)
            if (not st["streaming"] and st["streams_at"] is not None and now >= st["streams_at"] + stream_wait_s
                    and st["stream_tries"] < spec.retry.mission_retries):
                st["stream_tries"] += 1
                _request_streams(peer, m, spec, src, st)
    summary = {"node": spec.name, "sysid": spec.sysid, "sent": dict(sent), "received": dict(received),
               "received_by_uav": {k: dict(v) for k, v in received_by.items()},
               "uploaded": sorted(targets[s].name for s, st in state.items() if st["uploaded"])}
    log("summary", **summary)
    return summary


def _request_streams(peer: _Peer, m, spec: GcsSpec, src: int, st: dict) -> None:
    for sid, rate in spec.rates.requests():
        peer.send(m.MAVLink_request_data_stream_message(src, COMPONENT_AUTOPILOT, sid, rate, 1 if rate else 0))
    st["streams_at"] = time.time()


def _mission_start(peer: _Peer, m, tgt: GcsTarget, st: dict) -> None:
    st["pending"], st["tries"] = "count", 0
    _resend_mission(peer, m, tgt, st)


def _resend_mission(peer: _Peer, m, tgt: GcsTarget, st: dict) -> None:
    """(Re)send what the upload waits on an answer to: the count, or the last item asked for."""
    if st["pending"] == "count":
        peer.send(m.MAVLink_mission_count_message(tgt.sysid, COMPONENT_AUTOPILOT, len(tgt.waypoints),
                                                  m.MAV_MISSION_TYPE_MISSION))
    else:
        peer.send(_item(m, tgt, st["pending"][1]))
    st["pending_at"] = time.time()


def _item(m, tgt: GcsTarget, seq: int):
    lat, lon, alt = tgt.waypoints[seq]
    return m.MAVLink_mission_item_int_message(
        tgt.sysid, COMPONENT_AUTOPILOT, seq, m.MAV_FRAME_GLOBAL_RELATIVE_ALT_INT, m.MAV_CMD_NAV_WAYPOINT,
        1 if seq == 0 else 0, 1, 0.0, 2.0, 0.0, float("nan"), round(lat * 1e7), round(lon * 1e7), float(alt),
        m.MAV_MISSION_TYPE_MISSION)


def _send_command(peer: _Peer, m, src: int, st: dict) -> None:
    # DO_CHANGE_SPEED: param1 1 = ground speed, param2 m/s, param3 -1 = throttle unchanged
    peer.send(m.MAVLink_command_long_message(src, COMPONENT_AUTOPILOT, m.MAV_CMD_DO_CHANGE_SPEED, st["cmd_tries"],
                                             1.0, float(st["cmd"]["speed"]), -1.0, 0.0, 0.0, 0.0, 0.0))
    st["cmd_at"] = time.time()


def _gcs_handle(m, msg, typ: str, peer: _Peer, tgt: GcsTarget, st: dict, spec: GcsSpec, log) -> None:
    t = round(time.time() - spec.t0_unix, 4)
    if typ in ("GLOBAL_POSITION_INT", "ATTITUDE", "VFR_HUD", "SYS_STATUS") and not st["streaming"]:
        st["streaming"] = True
        log("streams", uav=tgt.name, result="started", requests=st["stream_tries"] + 1)
    if typ == "MISSION_REQUEST_INT" and msg.target_system == spec.sysid and st["pending"] is not None:
        if 0 <= msg.seq < len(tgt.waypoints):
            st["pending"], st["tries"] = ("item", msg.seq), 0
            _resend_mission(peer, m, tgt, st)
    elif typ == "MISSION_ACK" and msg.target_system == spec.sysid and st["pending"] is not None:
        ok = msg.type == m.MAV_MISSION_ACCEPTED
        st["pending"], st["uploaded"] = None, ok
        log("mission_upload", uav=tgt.name, result="accepted" if ok else f"rejected {msg.type}", t_s=t,
            items=len(tgt.waypoints), took_s=round(t - st["mission_t0"], 4))
    elif typ == "COMMAND_ACK" and msg.target_system == spec.sysid and st["cmd"] is not None \
            and msg.command == m.MAV_CMD_DO_CHANGE_SPEED:
        log("command_result", uav=tgt.name, window=st["cmd"]["window"],
            result="accepted" if msg.result == m.MAV_RESULT_ACCEPTED else f"result {msg.result}",
            tries=st["cmd_tries"] + 1)
        st["cmd"] = None


def read_log(path: Path) -> list[dict]:
    """The JSON lines of an endpoint's log (a torn last line, from a kill, is skipped)."""
    out = []
    for line in Path(path).read_text().splitlines():
        try:
            out.append(json.loads(line))
        except json.JSONDecodeError:
            continue
    return out


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(prog="python -m uavcas.emulation.apps.mavlink")
    ap.add_argument("role", choices=("uav", "gcs"))
    ap.add_argument("spec", type=Path, help="the endpoint's spec (JSON)")
    a = ap.parse_args(argv)
    try:
        text = a.spec.read_text()
        spec = UavSpec.model_validate_json(text) if a.role == "uav" else GcsSpec.model_validate_json(text)
    except (OSError, ValueError) as e:
        print(f"mavlink {a.role}: bad spec {a.spec}: {str(e).splitlines()[0]}", file=sys.stderr)
        return 2
    try:
        summary = run_uav(spec) if a.role == "uav" else run_gcs(spec)
    except (OSError, TimeoutError) as e:
        print(f"mavlink {a.role} {spec.name}: {e}", file=sys.stderr)
        return 1
    print(json.dumps(summary), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
