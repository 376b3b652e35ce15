"""The UAV end: an ArduCopter-like autopilot sending the plan's track as ArduCopter's streams."""

from __future__ import annotations

import socket
import time
from collections import Counter

from pymavlink.dialects.v20 import ardupilotmega

from uavcas import seeding
from uavcas.twin.track import local_to_geodetic

from . import signing
from .bridge import RadioBridge
from .commands import VehicleState
from .flight import Sensors
from .gps import POSITION_MESSAGES, GpsReceiver
from .link import Log, Peer, Periodic, Stop, await_t0, recv_all
from .params import param_rate_hz, param_value, vehicle_params
from .specs import COMPONENT_AUTOPILOT, UavSpec, mission_waypoints
from .streams import GROUP_BY_ID, STREAM_GROUPS, TERRAIN_REQUEST_MIN_INTERVAL_S
from .telemetry import TelemetryContext, build, terrain_request

SENSOR_STREAM = "mavlink-sensors"  # the noise stream's name (uavcas.seeding)


def run_uav(spec: UavSpec) -> dict:
    m = ardupilotmega
    stop = Stop()
    sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    sock.bind((spec.bind_ip, spec.bind_port))
    sock.setblocking(False)
    sent, received = Counter(), Counter()
    gcs = Peer(sock, (spec.gcs_ip, spec.gcs_port), spec.sysid, COMPONENT_AUTOPILOT, sent)
    signing.enable(gcs.mav, spec.signing)
    track = spec.track()
    waypoints = mission_waypoints(spec.site, track)
    sensors = Sensors(seeding.generator(spec.plan_seed, SENSOR_STREAM, spec.uav_index), spec.site.alt_m)
    params = vehicle_params(spec.sysid)
    spec = spec.model_copy(update={"t0_unix": await_t0(spec, stop)})
    log = Log(spec.log_path, spec.t0_unix)
    gps = GpsReceiver(spec.gps_path, log)  # true fixes unless the attack executor publishes a spoofer
    radio = RadioBridge(sock, spec)  # the telemetry radio's RADIO_STATUS (radio.py), on this socket
    deadline = spec.t0_unix + spec.duration_s
    now = time.time()
    heartbeat = Periodic(1.0, now)
    # every stream starts at ArduCopter's default rate, 0 Hz (SRn_* = 0): it sends what a GCS asks for
    streams = {g.name: Periodic(0.0, now) for g in STREAM_GROUPS if g.messages}
    terrain_at = [float("-inf")]
    plist = {"next": None, "pace": Periodic(0.0, now), "sent": 0}  # the PARAM_REQUEST_LIST in progress
    mission: dict = {"count": None, "items": {}, "from_": None, "asked": None, "seq": None, "tries": 0}
    vehicle = VehicleState()
    while not stop.flag and (now := time.time()) < deadline:
        waits = [heartbeat.next, plist["pace"].next if plist["next"] is not None else deadline]
        for data, addr in recv_all(sock, _wait(now, deadline, waits, streams, mission, spec.retry.timeout_s)):
            for msg in gcs.parse(data):
                typ = msg.get_type()
                received[typ] += 1
                if typ == "BAD_DATA" and "signature" in str(getattr(msg, "reason", "")):
                    log("rejected", reason=msg.reason, src=f"{addr[0]}:{addr[1]}")  # signing on: no answer
                if typ == "BAD_DATA" or msg.get_srcSystem() == spec.sysid:
                    continue
                if getattr(msg, "target_system", spec.sysid) != spec.sysid:
                    continue
                if typ == "REQUEST_DATA_STREAM":
                    rate = float(msg.req_message_rate if msg.start_stop else 0)
                    # MAV_DATA_STREAM_ALL: every stream but PARAMS (GCS_Common.cpp handle_request_data_stream)
                    names = (list(streams) if msg.req_stream_id == m.MAV_DATA_STREAM_ALL
                             else [GROUP_BY_ID[msg.req_stream_id].name] if msg.req_stream_id in GROUP_BY_ID else [])
                    for name in names:
                        if name in streams and streams[name].period != (1.0 / rate if rate > 0 else None):
                            streams[name] = Periodic(rate, time.time())
                elif typ == "PARAM_REQUEST_LIST":  # (re)start the list from the first parameter
                    plist.update(next=0, pace=Periodic(param_rate_hz(spec.telem_baud), time.time()))
                    log("param_request_list", count=len(params))
                elif typ == "PARAM_REQUEST_READ":  # answered at once, ahead of the list
                    idx = msg.param_index
                    if idx < 0 or idx >= 65535:  # by name
                        name = msg.param_id.rstrip("\x00") if isinstance(msg.param_id, str) else ""
                        idx = next((i for i, p in enumerate(params) if p.name == name), -1)
                    if 0 <= idx < len(params):
                        gcs.send(param_value(m, params, idx))
                elif typ == "MISSION_COUNT":
                    mission.update(count=msg.count, items={}, from_=(msg.get_srcSystem(), msg.get_srcComponent()),
                                   asked=None, tries=0)
                    log("mission_count", count=msg.count)
                    _ask_next(gcs, m, mission, spec, log)
                elif (typ == "MISSION_ITEM_INT" and mission["count"]
                      and mission["asked"] is not None and msg.seq == mission["seq"]):
                    # only the item asked for: a duplicate (both ends retried) must not ask again
                    mission["items"][msg.seq] = (msg.x / 1e7, msg.y / 1e7, msg.z)
                    _ask_next(gcs, m, mission, spec, log)
                elif typ == "COMMAND_LONG":
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
        if heartbeat.due(now):
            gcs.send(m.MAVLink_heartbeat_message(
                m.MAV_TYPE_QUADROTOR, m.MAV_AUTOPILOT_ARDUPILOTMEGA,
                m.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED | m.MAV_MODE_FLAG_SAFETY_ARMED | m.MAV_MODE_FLAG_STABILIZE_ENABLED
                | m.MAV_MODE_FLAG_GUIDED_ENABLED | m.MAV_MODE_FLAG_AUTO_ENABLED,
                vehicle.custom_mode, m.MAV_STATE_ACTIVE, 3))
            radio.after_heartbeat(t)  # SiK reports once per heartbeat it passes on
        if plist["next"] is not None and plist["pace"].due(now):
            gcs.send(param_value(m, params, plist["next"]))
            plist["sent"] += 1
            plist["next"] = plist["next"] + 1 if plist["next"] + 1 < len(params) else None
        due = [g for g in STREAM_GROUPS if g.name in streams and streams[g.name].due(now)]
        if not due:
            continue
        ctx = TelemetryContext(battery=spec.battery, mission_count=len(waypoints), sensors=sensors,
                               custom_mode=vehicle.custom_mode)
        # The GPS receiver's (possibly spoofed) fix goes into GPS_RAW_INT and GLOBAL_POSITION_INT
        # alone (gps.report below), the messages the gps_spoof truth rule labels; the other
        # position-bearing messages (LOCAL_POSITION_NED, AHRS2, TERRAIN_REPORT, the navigation to
        # the next waypoint) carry the physical track until that rule labels them too (flight.py).
        state = sensors.state(track, spec.site, t, now, track.at(t), waypoints)
        for g in due:
            for typ in g.messages:
                if typ in POSITION_MESSAGES:  # a GPS fix, of this instant (gps.py: spoofing decided then)
                    gps.report(track, spec.t0_unix, lambda q, tq: gcs.send(build(
                        m, typ, state.model_copy(update={"fix": q, "t_s": tq, **_geo(spec.site, q)}), ctx)))
                else:
                    gcs.send(build(m, typ, state, ctx))
            if g.name == "EXTRA3" and now - terrain_at[0] >= TERRAIN_REQUEST_MIN_INTERVAL_S:
                terrain_at[0] = now  # AP_Terrain: grid blocks still missing, last request >= 2 s ago
                gcs.send(terrain_request(m, state))
    summary = {"node": spec.name, "sysid": spec.sysid, "sent": dict(sent), "received": dict(received),
               "mission_items": len(mission["items"]), "last_speed_mps": vehicle.speed_mps,
               "custom_mode": vehicle.custom_mode, "gps": gps.summary(), "params_sent": plist["sent"],
               "radio_sent": dict(radio.sent)}
    log("summary", **summary)
    return summary


def _geo(site, q) -> dict:
    lat, lon, amsl = local_to_geodetic(site, q.x_m, q.y_m, q.z_m)
    return {"lat_deg": lat, "lon_deg": lon, "amsl_m": amsl, "groundspeed_mps": q.groundspeed_mps}


def _wait(now, deadline, waits, streams, mission, timeout_s: float) -> float:
    """Seconds until the UAV's next own action: a message due, a mission retry, the deadline."""
    nxt = [deadline, *waits] + [p.next for p in streams.values() if p.period is not None]
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
