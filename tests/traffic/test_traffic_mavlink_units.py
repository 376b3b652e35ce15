"""The MAVLink endpoints (traffic/mavlink/) talking over UDP on 127.0.0.1, no namespaces.

A relay between the two records every datagram both ways, so the test checks the bytes on the
wire: each one is one MAVLink 2 frame that pymavlink parses with a valid CRC.
"""

from __future__ import annotations

from collections import Counter

import pytest

from helpers.mavlink_relay import Relay, bs0_uav0_specs, free_port, parse_each, run_endpoints, type_of
from uavcas.traffic import mavlink as mv
from uavcas.twin.plan import plan
from uavcas.twin.track import Track, geodetic_to_local

pytestmark = pytest.mark.slow
CFG = "benign-6-2-telemetry-logdist-adaptive-random-30-95"


def test_gcs_and_uav_exchange_mission_commands_and_streams_over_udp(tmp_path):
    p = plan(CFG, seed=14, windows=3, window_s=1.5)
    gcs_port = free_port()
    relay = Relay(gcs_port)
    relay.start()
    gspec, uspec = bs0_uav0_specs(tmp_path, p, gcs_port, relay, p.duration_s + 0.5)
    # a served UAV whose system id is SiK's (uav50 has 51): uav0's radio frames must not pass for it
    sik = mv.GcsTarget(name="uav50", sysid=51, waypoints=[(35.7, -78.7, 30.0)], speeds_mps=[0.0] * len(p.windows))
    gspec = gspec.model_copy(update={"uavs": [*gspec.uavs, sik]})
    run_endpoints(tmp_path, gspec, uspec, relay)

    glog, ulog = mv.read_log(gspec.log_path), mv.read_log(uspec.log_path)
    assert not [e for e in glog if e.get("uav") == "uav50"]
    assert not [e for e in glog if e["event"] == "summary"][0]["received_by_uav"]["uav50"]
    uploads = [e for e in glog if e["event"] == "mission_upload"]
    assert [e["result"] for e in uploads] == ["accepted"] and uploads[0]["items"] == 3
    assert uploads[0]["t_s"] < 1.2  # at once (both ends were up before t0) but for one 0.5 s retry
    # the first item and the first command were dropped by the relay: both were resent once
    assert not relay.drop_once
    # 3 items + the lost one again (twice when the GCS's and the UAV's timers both fire)
    assert 4 <= sum(type_of(d) == "MISSION_ITEM_INT" for _, d in relay.down) <= 5
    acks = {e["window"]: (e["result"], e["tries"]) for e in glog if e["event"] == "command_result"}
    assert acks == {1: ("accepted", 2), 2: ("accepted", 1)}
    sent_at = {e["window"]: e["t_s"] for e in glog if e["event"] == "command_sent"}
    assert sent_at[1] == pytest.approx(1.5, abs=0.1) and sent_at[2] == pytest.approx(3.0, abs=0.1)
    speeds = [e["param2"] for e in ulog if e["event"] == "command"]
    track = Track.of(p, "uav0")
    assert speeds[:2] == pytest.approx([track.speed_in_window_mps(1), track.speed_in_window_mps(2)], rel=1e-6)
    assert [e["result"] for e in ulog if e["event"] == "mission_receive"] == ["accepted"]

    up, down = parse_each(relay.up), parse_each(relay.down)
    assert {m.get_type() for _, m in down} >= {"HEARTBEAT", "REQUEST_DATA_STREAM", "MISSION_COUNT",
                                               "MISSION_ITEM_INT", "COMMAND_LONG"}
    assert all(m.get_srcSystem() == 255 for _, m in down)
    # up: the autopilot's frames, and its radio's RADIO_STATUS under SiK's ids (radio.py)
    assert all(m.get_srcSystem() == 1 for _, m in up if m.get_type() != "RADIO_STATUS")
    assert {(m.get_srcSystem(), m.get_srcComponent()) for _, m in up if m.get_type() == "RADIO_STATUS"} == {(51, 68)}
    # rates: from the first streamed message to the UAV's end, each type at its configured rate
    first = min(t for t, m in up if m.get_type() == "GLOBAL_POSITION_INT")
    span = max(t for t, _ in up) - first
    counts = Counter(m.get_type() for t, m in up if t >= first)
    for typ, hz in mv.StreamRates().expected_hz().items():
        assert abs(counts[typ] - hz * span) <= 0.15 * hz * span + 2, (typ, counts[typ], hz * span)
    # every position is the plan's track at its time_boot_ms, to the centimetre
    for _, m in up:
        if m.get_type() == "GLOBAL_POSITION_INT":
            x, y, z = geodetic_to_local(p.site, m.lat / 1e7, m.lon / 1e7, m.alt / 1000)
            q = track.at(m.time_boot_ms / 1000)
            assert abs(x - q.x_m) < 0.02 and abs(y - q.y_m) < 0.02 and abs(z - q.z_m) < 0.002
    hb = next(m for _, m in up if m.get_type() == "HEARTBEAT")
    assert (hb.type, hb.autopilot, hb.custom_mode) == (2, 3, 3)  # QUADROTOR, ARDUPILOTMEGA, Copter AUTO
    summary = [e for e in glog if e["event"] == "summary"][0]
    relayed = sum(m.get_type() == "GLOBAL_POSITION_INT" for _, m in up)
    # both ends stop at the same deadline: the last one relayed may arrive after the GCS stopped
    assert relayed - 1 <= summary["received_by_uav"]["uav0"]["GLOBAL_POSITION_INT"] <= relayed


def test_a_lost_stream_request_is_sent_again_at_the_next_periodic_request(tmp_path):
    # MAVProxy sends MAV_DATA_STREAM_ALL to every detected vehicle and again every 15 s
    # (msg_period): a request lost on a loaded downlink is repaired by the next one. Here the
    # period is 2 s so that the test is short; the first request is lost.
    from pymavlink.dialects.v20 import common

    p = plan(CFG, seed=14, windows=2, window_s=3.0)
    gcs_port = free_port()
    relay = Relay(gcs_port, drop_once=("REQUEST_DATA_STREAM",))
    relay.start()
    gspec, uspec = bs0_uav0_specs(tmp_path, p, gcs_port, relay, p.duration_s)
    gspec = gspec.model_copy(update={"rates": mv.StreamRates(rerequest_s=2.0)})
    t0 = run_endpoints(tmp_path, gspec, uspec, relay)

    assert not relay.drop_once
    down, up = parse_each(relay.down), parse_each(relay.up)
    requests = [(t, m.req_stream_id, m.req_message_rate) for t, m in down if m.get_type() == "REQUEST_DATA_STREAM"]
    assert {(s, r) for _, s, r in requests} == {(common.MAV_DATA_STREAM_ALL, 4)}  # one request, all streams
    assert requests[0][0] - t0 < 0.3  # at the vehicle's first HEARTBEAT
    assert requests[1][0] - t0 == pytest.approx(2.0, abs=0.3)  # the periodic one repairs the loss
    first = min(t for t, m in up if m.get_type() == "ATTITUDE")
    assert requests[1][0] < first < requests[1][0] + 0.3
    started = {e["group"]: e["requests"] for e in mv.read_log(gspec.log_path) if e["event"] == "stream"}
    assert set(started) == {"RAW_SENSORS", "EXTENDED_STATUS", "POSITION", "RC_CHANNELS", "EXTRA1", "EXTRA2",
                            "EXTRA3"} and set(started.values()) == {2}
