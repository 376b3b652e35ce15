"""The BS end: a ground station that requests streams and parameters, uploads missions and
commands speeds, as MAVProxy does (MAVProxy at f76c4d3d: mavproxy.py `set_stream_rates`,
modules/mavproxy_param.py `ParamState.fetch_check`; `specs.StreamRates`, `params`)."""

from __future__ import annotations

import socket
import time
from collections import Counter

from pymavlink.dialects.v20 import ardupilotmega

from . import signing
from .link import Log, Peer, Periodic, Stop, await_t0, recv_all
from .specs import COMPONENT_AUTOPILOT, COMPONENT_GCS, GcsSpec, GcsTarget
from .streams import GROUP_OF

# MAVProxy's parameter fetch (mavproxy_param.py ParamState): `fetch_check` runs once a second
# (`param_period = mavutil.periodic_event(1)`); with no parameter yet it sends PARAM_REQUEST_LIST;
# with some missing and none heard for 1 s (`master.time_since('PARAM_VALUE') >= 1`) it asks for
# at most 10 missing indices with PARAM_REQUEST_READ, and asks for the next ones at once when all
# of those have come (`fetch_set` empty -> `fetch_check(force=True)`). MAVProxy downloads by MAVLink
# FTP first where the vehicle offers it and falls back to this when FTP fails (`ftp_failed`); the
# autopilot here serves no FTP, so this is the path.
PARAM_CHECK_S = 1.0
PARAM_QUIET_S = 1.0
PARAM_READ_BATCH = 10


def run_gcs(spec: GcsSpec) -> dict:
    m = ardupilotmega
    stop = Stop()
    sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
    sock.bind((spec.bind_ip, spec.port))
    sock.setblocking(False)
    spec = spec.model_copy(update={"t0_unix": await_t0(spec, stop)})
    log = Log(spec.log_path, spec.t0_unix)
    log("listening", port=spec.port, uavs=[u.name for u in spec.uavs])
    sent, received = Counter(), Counter()
    targets = {u.sysid: u for u in spec.uavs}
    received_by: dict[str, Counter] = {u.name: Counter() for u in spec.uavs}
    peers: dict[int, Peer] = {}
    state: dict[int, dict] = {}
    deadline = spec.t0_unix + spec.duration_s
    # one signing state checks every datagram (its streams' last timestamps persist across the
    # per-datagram parsers); each peer signs what it sends with its own
    checks = signing.new_signing_state(spec.signing) if spec.signing is not None else None
    # MAVProxy's msg_period: every detected vehicle's streams are requested again every
    # `rerequest_s` (15 s), which repairs a request a loaded downlink lost.
    rerequest = Periodic(1.0 / spec.rates.rerequest_s, time.time() + spec.rates.rerequest_s)
    while not stop.flag and (now := time.time()) < deadline:
        waits = [deadline, rerequest.next]
        for sysid, st in state.items():
            waits += [st["hb"].next, st["param_check"].next,
                      st["pending_at"] + spec.retry.timeout_s if st["pending"] else deadline,
                      st["cmd_at"] + spec.retry.timeout_s if st["cmd"] else deadline]
        for k in range(1, spec.n_windows):
            if spec.t0_unix + k * spec.window_s > now:
                waits.append(spec.t0_unix + k * spec.window_s)
                break
        for data, addr in recv_all(sock, max(0.0, min(waits) - now)):
            probe = m.MAVLink(None)  # one message per datagram: a fresh parser per datagram
            probe.robust_parsing = True
            if checks is not None:
                probe.signing = checks
            for msg in probe.parse_buffer(data) or []:
                typ, src = msg.get_type(), msg.get_srcSystem()
                received[typ] += 1
                # a UAV is its autopilot's (system, component): its radio's RADIO_STATUS comes under
                # SiK's fixed ids (radio.py: system 51 = uav50's own id), from any UAV's address
                if typ == "BAD_DATA" or src not in targets or msg.get_srcComponent() != COMPONENT_AUTOPILOT:
                    continue
                received_by[targets[src].name][typ] += 1
                if src not in peers:
                    peers[src] = Peer(sock, addr, spec.sysid, COMPONENT_GCS, sent)
                    signing.enable(peers[src].mav, spec.signing)
                    state[src] = {"hb": Periodic(spec.rates.heartbeat_rate_hz, time.time()), "pending": None,
                                  "pending_at": 0.0, "tries": 0, "mission_t0": time.time() - spec.t0_unix,
                                  "uploaded": False, "cmd": None, "cmd_at": 0.0, "cmd_tries": 0,
                                  "stream_requests": 0, "streams_heard": set(),
                                  "param_check": Periodic(1.0 / PARAM_CHECK_S, time.time() + PARAM_CHECK_S),
                                  "params": {}, "param_count": 0, "param_at": 0.0, "fetch_set": None,
                                  "param_reads": 0, "param_lists": 0, "params_done": False,
                                  "window": max(0, int((time.time() - spec.t0_unix) // spec.window_s))}
                    log("heard", uav=targets[src].name, sysid=src)
                    _mission_start(peers[src], m, targets[src], state[src])
                if typ == "HEARTBEAT" and msg.type != m.MAV_TYPE_GCS and state[src]["stream_requests"] == 0:
                    # detected (mavproxy_link.py master_callback): its streams are requested now
                    _request_streams(peers[src], m, spec, src, state[src])
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
            if st["param_check"].due(now):
                _fetch_check(peer, m, src, st)
        if rerequest.due(now):  # MAVProxy's msg_period: every detected vehicle, every 15 s
            for src, st in state.items():
                if st["stream_requests"]:
                    _request_streams(peers[src], m, spec, src, st)
    summary = {"node": spec.name, "sysid": spec.sysid, "sent": dict(sent), "received": dict(received),
               "received_by_uav": {k: dict(v) for k, v in received_by.items()},
               "params": {targets[s].name: len(st["params"]) for s, st in state.items()},
               "uploaded": sorted(targets[s].name for s, st in state.items() if st["uploaded"])}
    log("summary", **summary)
    return summary


def _request_streams(peer: Peer, m, spec: GcsSpec, src: int, st: dict) -> None:
    """REQUEST_DATA_STREAM as MAVProxy sends it: MAV_DATA_STREAM_ALL at `streamrate`, start."""
    for sid, rate in spec.rates.requests():
        peer.send(m.MAVLink_request_data_stream_message(src, COMPONENT_AUTOPILOT, sid, rate, 1))
    st["stream_requests"] += 1


def _fetch_check(peer: Peer, m, src: int, st: dict, force: bool = False) -> None:
    """MAVProxy's `ParamState.fetch_check` (module comment): the list, or the missing ones."""
    if not st["params"]:
        peer.send(m.MAVLink_param_request_list_message(src, COMPONENT_AUTOPILOT))
        st["param_lists"] += 1
    elif st["param_count"] and len(st["params"]) < st["param_count"] and (
            force or time.time() - st["param_at"] >= PARAM_QUIET_S):
        missing = [i for i in range(st["param_count"]) if i not in st["params"]][:PARAM_READ_BATCH]
        for idx in missing:
            peer.send(m.MAVLink_param_request_read_message(src, COMPONENT_AUTOPILOT, b"", idx))
        st["fetch_set"] = (st["fetch_set"] or set()) | set(missing)
        st["param_reads"] += len(missing)


def _mission_start(peer: Peer, m, tgt: GcsTarget, st: dict) -> None:
    st["pending"], st["tries"] = "count", 0
    _resend_mission(peer, m, tgt, st)


def _resend_mission(peer: Peer, m, tgt: GcsTarget, st: dict) -> None:
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


def _send_command(peer: Peer, m, src: int, st: dict) -> None:
    # DO_CHANGE_SPEED: param1 1 = ground speed, param2 m/s, param3 -1 = throttle unchanged
    peer.send(m.MAVLink_command_long_message(src, COMPONENT_AUTOPILOT, m.MAV_CMD_DO_CHANGE_SPEED, st["cmd_tries"],
                                             1.0, float(st["cmd"]["speed"]), -1.0, 0.0, 0.0, 0.0, 0.0))
    st["cmd_at"] = time.time()


def _gcs_handle(m, msg, typ: str, peer: Peer, tgt: GcsTarget, st: dict, spec: GcsSpec, log) -> None:
    t = round(time.time() - spec.t0_unix, 4)
    if typ in GROUP_OF and GROUP_OF[typ] not in st["streams_heard"]:
        st["streams_heard"].add(GROUP_OF[typ])
        log("stream", uav=tgt.name, group=GROUP_OF[typ], message=typ, result="started", t_s=t,
            requests=st["stream_requests"])
    if typ == "PARAM_VALUE":
        _param_value(m, msg, peer, tgt, st, spec, log, t)
    elif typ == "MISSION_REQUEST_INT" and msg.target_system == spec.sysid and st["pending"] is not None:
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


def _param_value(m, msg, peer: Peer, tgt: GcsTarget, st: dict, spec: GcsSpec, log, t: float) -> None:
    """MAVProxy's handling of PARAM_VALUE (mavproxy_param.py handle_mavlink_packet)."""
    st["param_at"] = time.time()
    if st["fetch_set"] is not None:
        st["fetch_set"].discard(msg.param_index)
    new = msg.param_index not in (-1, 65535) and msg.param_index not in st["params"]
    if new:
        st["params"][msg.param_index] = msg.param_value
    st["param_count"] = msg.param_count
    if new and len(st["params"]) == msg.param_count and not st["params_done"]:
        st["params_done"], st["fetch_set"] = True, None
        log("params", uav=tgt.name, result="complete", count=msg.param_count, t_s=t, lists=st["param_lists"],
            reads=st["param_reads"])
    if st["fetch_set"] is not None and not st["fetch_set"]:
        _fetch_check(peer, m, msg.get_srcSystem(), st, force=True)
