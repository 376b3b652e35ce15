"""The UAV end: an ArduCopter-like autopilot sending the plan's track as MAVLink telemetry."""

from __future__ import annotations

import math
import socket
import time
from collections import Counter

from pymavlink.dialects.v20 import common

from uavcas.twin.track import local_to_geodetic

from . import signing
from .bridge import RadioBridge
from .commands import VehicleState
from .gps import POSITION_MESSAGES, GpsReceiver, course_deg
from .link import Log, Peer, Periodic, Stop, await_t0, recv_all
from .specs import COMPONENT_AUTOPILOT, GPS_FIX_3D, GPS_SATELLITES, STREAM_MESSAGES, UavSpec


def run_uav(spec: UavSpec) -> dict:
    m = common
    stop = Stop()
    sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    sock.bind((spec.bind_ip, spec.bind_port))
    sock.setblocking(False)
    sent, received = Counter(), Counter()
    gcs = Peer(sock, (spec.gcs_ip, spec.gcs_port), spec.sysid, COMPONENT_AUTOPILOT, sent)
    signing.enable(gcs.mav, spec.signing)
    track = spec.track()
    spec = spec.model_copy(update={"t0_unix": await_t0(spec, stop)})
    log = Log(spec.log_path, spec.t0_unix)
    gps = GpsReceiver(spec.gps_path, log)  # true fixes unless the attack executor publishes a spoofer
    radio = RadioBridge(sock, spec)  # the telemetry radio's RADIO_STATUS (radio.py), on this socket
    deadline = spec.t0_unix + spec.duration_s
    now = time.time()
    heartbeat = Periodic(1.0, now)
    streams = {sid: Periodic(0.0, now) for sid in STREAM_MESSAGES}  # ArduCopter default: 0 Hz
    mission: dict = {"count": None, "items": {}, "from_": None, "asked": None, "seq": None, "tries": 0}
    vehicle = VehicleState()
    while not stop.flag and (now := time.time()) < deadline:
        for data, addr in recv_all(sock, _wait(now, deadline, heartbeat, streams, mission, spec.retry.timeout_s)):
            for msg in gcs.parse(data):
                typ = msg.get_type()
                received[typ] += 1
                if typ == "BAD_DATA" and "signature" in str(getattr(msg, "reason", "")):
                    log("rejected", reason=msg.reason, src=f"{addr[0]}:{addr[1]}")  # signing on: no answer
                if typ == "BAD_DATA" or msg.get_srcSystem() == spec.sysid:
                    continue
                if typ == "REQUEST_DATA_STREAM" and msg.target_system == spec.sysid:
                    ids = STREAM_MESSAGES if msg.req_stream_id == m.MAV_DATA_STREAM_ALL else [msg.req_stream_id]
                    for sid in ids:
                        if sid in streams:
                            rate = msg.req_message_rate if msg.start_stop else 0
                            streams[sid] = Periodic(float(rate), time.time())
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
                    result = vehicle.command(m, msg)
                    # the answer goes back to the sender's address (a command's link)
                    gcs.send_to(m.MAVLink_command_ack_message(msg.command, result, 0, 0, msg.get_srcSystem(),
                                                              msg.get_srcComponent()), addr)
                    log("command", command=int(msg.command), confirmation=int(msg.confirmation),
                        param2=float(msg.param2), result=int(result), src=f"{addr[0]}:{addr[1]}",
                        mode=vehicle.custom_mode)
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
                vehicle.custom_mode, m.MAV_STATE_ACTIVE, 3))
            radio.after_heartbeat(t)  # SiK reports once per heartbeat it passes on
        for sid, per in streams.items():
            if per.due(now):
                for typ in STREAM_MESSAGES[sid]:
                    if typ in POSITION_MESSAGES:  # a GPS fix, of this instant (gps.py: spoofing decided then)
                        gps.report(track, spec.t0_unix, lambda q, tq: gcs.send(_telemetry(m, typ, spec, q, tq)))
                    else:
                        gcs.send(_telemetry(m, typ, spec, p, t))
    summary = {"node": spec.name, "sysid": spec.sysid, "sent": dict(sent), "received": dict(received),
               "mission_items": len(mission["items"]), "last_speed_mps": vehicle.speed_mps,
               "custom_mode": vehicle.custom_mode, "gps": gps.summary(), "radio_sent": dict(radio.sent)}
    log("summary", **summary)
    return summary


def _wait(now, deadline, heartbeat, streams, mission, timeout_s: float) -> float:
    """Seconds until the UAV's next own action: a message due, a mission retry, the deadline."""
    nxt = [deadline, heartbeat.next] + [p.next for p in streams.values() if p.period is not None]
    if mission["asked"] is not None:
        nxt.append(mission["asked"] + timeout_s)
    return max(0.0, min(nxt) - now)


def _ask_next(gcs: Peer, m, mission: dict, spec: UavSpec, log, resend: bool = False) -> None:
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
            round(gs * 100), round(course_deg(p) * 100) % 36000, GPS_SATELLITES)
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
