"""ArduCopter's streams (traffic/mavlink/streams.py), the flight model behind every field
(flight.py, telemetry.py), the parameter list (params.py), and both endpoints over loopback UDP."""

from __future__ import annotations

import math
from collections import Counter

import numpy as np
import pytest
from pymavlink.dialects.v20 import ardupilotmega as apm

from helpers.mavlink_relay import Relay, bs0_uav0_specs, free_port, parse_each, run_endpoints
from uavcas import seeding
from uavcas.mavlink_capture import decode_datagram
from uavcas.traffic import mavlink as mv
from uavcas.traffic.mavlink import flight, params, streams, telemetry
from uavcas.twin.model import Site
from uavcas.twin.plan import plan
from uavcas.twin.track import Track

CFG = "benign-6-2-telemetry-logdist-adaptive-random-30-95"
G = flight.GRAVITY_MSS


def test_the_stream_table_is_arducopters_without_optional_hardware():
    names = [g.name for g in streams.STREAM_GROUPS]
    assert names == ["RAW_SENSORS", "EXTENDED_STATUS", "POSITION", "RC_CHANNELS", "EXTRA1", "EXTRA2", "EXTRA3",
                     "ADSB"]
    every = [msg for g in streams.STREAM_GROUPS for msg in (*g.messages, *g.left_out)]
    assert len(every) == len(set(every))  # a message is in one group only
    for msg in every:  # each is a message of the dialect both ends speak
        assert hasattr(apm, f"MAVLINK_MSG_ID_{msg}"), msg
    assert set(telemetry.BUILDERS) == set(streams.STREAMED)  # every streamed message has a builder
    assert len(streams.STREAMED) == 25
    # 25 messages per tick, HEARTBEAT at 1 Hz, TERRAIN_REQUEST at most every 2 s
    assert streams.frames_per_s(3) == pytest.approx(25 * 3 + 1 + 0.5)
    assert streams.frames_per_s(4) == pytest.approx(25 * 4 + 1 + 0.5)
    assert mv.StreamRates().stream_rate_hz == 4 and mv.StreamRates().requests() == [(apm.MAV_DATA_STREAM_ALL, 4)]


def test_arducopters_parameters_with_types_and_the_pace_of_a_57600_baud_port():
    ps = params.default_params()
    assert len(ps) == 1095 and len({p.name for p in ps}) == 1095
    assert all(1 <= len(p.name) <= 16 and p.name.isascii() for p in ps)
    by = {p.name: p for p in ps}
    assert by["WPNAV_ACCEL"].value == 250 and by["WPNAV_ACCEL"].mav_type == apm.MAV_PARAM_TYPE_REAL32
    assert by["FRAME_CLASS"].mav_type == apm.MAV_PARAM_TYPE_INT8
    assert by["LOG_BITMASK"].mav_type == apm.MAV_PARAM_TYPE_INT32
    mine = {p.name: p.value for p in params.vehicle_params(7)}
    assert mine["SYSID_THISMAV"] == 7 and mine["BATT_MONITOR"] == 4 and mine["WPNAV_ACCEL"] == 250
    assert params.PARAM_RATE_HZ == pytest.approx(0.3 * 5760 / 37)  # 46.7 a second
    msg = params.param_value(apm, params.vehicle_params(7), 3)
    assert (msg.param_count, msg.param_index) == (1095, 3)


def _sensors(seed=1, index=0):
    return flight.Sensors(seeding.generator(seed, "mavlink-sensors", index), 0.0,
                          noise=flight.SensorNoise(accel_mps2=0.0, gyro_radps=0.0, pressure_pa=0.0, mag_mgauss=0.0))


def _state(track, t, sensors=None):
    p = track.at(t)
    site = Site()
    wps = [(0.0, 0.0, z) for *_, z in track.positions_m]
    return (sensors or _sensors()).state(track, site, t, 1.7e9 + t, p, wps)


def test_a_hovering_copter_is_level_reads_one_g_up_and_spins_at_hover_throttle():
    s = _state(Track((0.0, 10.0), ((0.0, 0.0, 50.0), (0.0, 0.0, 50.0))), 5.0)
    assert s.roll_rad == 0.0 and s.pitch_rad == 0.0
    assert s.accel_mps2 == pytest.approx((0.0, 0.0, -G))  # specific force: up, i.e. -z in FRD
    assert s.throttle == pytest.approx(0.35)  # MOT_THST_HOVER
    assert s.motor_pwm_us == (1430,) * 4  # 1000 + (0.15 + 0.8 * 0.35) * 1000
    # ISA at 50 m: 1007.26 hPa, 14.675 degC
    assert s.pressure_hpa == pytest.approx(1007.26, abs=0.01) and s.temperature_c == pytest.approx(14.675)
    assert s.mag_mgauss == pytest.approx(flight.MagField().ned())  # level, facing north: the field itself


def test_cruising_north_pitches_nose_down_against_drag_and_the_imu_reads_the_drag():
    v = 10.0
    s = _state(Track((0.0, 10.0, 20.0), ((0.0, 0.0, 50.0), (0.0, 100.0, 50.0), (0.0, 200.0, 50.0))), 15.0)
    want = math.atan((v / flight.REF_SPEED_MPS) ** 2)  # SITL's drag: 45 deg at 15.08 m/s
    assert s.pitch_rad == pytest.approx(-want) and s.roll_rad == pytest.approx(0.0, abs=1e-12)
    assert s.accel_mps2[0] == pytest.approx(-G * math.sin(want))  # drag: backwards
    assert s.accel_mps2[2] == pytest.approx(-G * math.cos(want))
    assert s.throttle == pytest.approx(0.35 / math.cos(want))


def test_a_turn_at_a_window_boundary_banks_at_wpnav_accel_for_dv_over_accel_seconds():
    # north at 5 m/s, then east at 5 m/s from t = 10: |dv| = 7.07 m/s at WPNAV_ACCEL 2.5 m/s^2: 2.83 s
    tr = Track((0.0, 10.0, 20.0), ((0.0, 0.0, 50.0), (0.0, 50.0, 50.0), (50.0, 50.0, 50.0)))
    akin, _ = flight.needed_acceleration(tr, 11.0)
    assert math.hypot(akin[0], akin[1]) == pytest.approx(2.5)
    assert akin[0] / 2.5 == pytest.approx(math.sqrt(0.5)) and akin[1] / 2.5 == pytest.approx(-math.sqrt(0.5))
    assert flight.needed_acceleration(tr, 12.9)[0] == (0.0, 0.0, 0.0)
    s = _state(tr, 11.0)  # heading east, braking the northward speed: it banks (rolls) to the south
    assert s.roll_rad > 0.1 and s.pitch_rad < 0  # right side down (south, facing east); nose down


def test_noise_is_seeded_per_plan_and_uav():
    tr = Track((0.0, 10.0), ((0.0, 0.0, 50.0), (0.0, 0.0, 50.0)))
    noisy = [flight.Sensors(seeding.generator(s, "mavlink-sensors", i), 0.0) for s, i in ((1, 0), (1, 0), (1, 1))]
    a, b, c = (_state(tr, 1.0, n) for n in noisy)
    assert a.accel_mps2 == b.accel_mps2 and a.accel_mps2 != c.accel_mps2
    assert np.std([_state(tr, 1.0, noisy[0]).accel_mps2[0] for _ in range(400)]) == pytest.approx(
        flight.SensorNoise().accel_mps2, rel=0.2)


def test_every_message_packs_and_the_capture_reader_decodes_it():
    tr = Track((0.0, 10.0, 20.0), ((0.0, 0.0, 50.0), (0.0, 100.0, 60.0), (30.0, 100.0, 60.0)))
    s = _state(tr, 12.0)
    ctx = telemetry.TelemetryContext(battery=mv.BatterySpec(), mission_count=3, sensors=_sensors())
    mav = apm.MAVLink(None, srcSystem=1, srcComponent=1)
    for name in (*streams.STREAMED, "TERRAIN_REQUEST"):
        msg = telemetry.terrain_request(apm, s) if name == "TERRAIN_REQUEST" else telemetry.build(apm, name, s, ctx)
        rows = decode_datagram(msg.pack(mav), apm)
        assert len(rows) == 1 and rows[0]["msg_name"] == name and rows[0]["crc_ok"], (name, rows)
    nav = telemetry.build(apm, "NAV_CONTROLLER_OUTPUT", s, ctx)
    assert nav.wp_dist == round(math.hypot(30.0 - s.fix.x_m, 100.0 - s.fix.y_m)) and nav.target_bearing == 90
    assert telemetry.build(apm, "MISSION_CURRENT", s, ctx).seq == 2  # window 1: flying to item 2


def test_the_plan_records_the_stream_rate():
    assert plan(CFG, seed=1, windows=1).mavlink_stream_hz == 4  # MAVProxy's streamrate
    assert plan(CFG, seed=1, windows=1, stream_hz=3).mavlink_stream_hz == 3
    for bad in (0, 51, 2.5, True):
        with pytest.raises(ValueError, match="stream_hz"):
            plan(CFG, seed=1, windows=1, stream_hz=bad)


@pytest.mark.slow  # 10 s of two endpoints
def test_both_ends_stream_ardupilots_mix_at_3_hz_and_fetch_every_parameter_over_udp(tmp_path):
    p = plan(CFG, seed=14, windows=2, window_s=4.0, stream_hz=3)
    gcs_port = free_port()
    lost = Counter()

    def drop(data):  # every 40th PARAM_VALUE is lost on the way up: the GCS must read them again
        if data[7:10] == bytes((22, 0, 0)):
            lost["n"] += 1
            return lost["n"] % 40 == 0
        return False

    relay = Relay(gcs_port, drop_once=(), drop_up=drop)
    relay.start()
    gspec, uspec = bs0_uav0_specs(tmp_path, p, gcs_port, relay, p.duration_s)
    gspec = gspec.model_copy(update={"rates": mv.StreamRates(stream_rate_hz=p.mavlink_stream_hz)})
    uspec = uspec.model_copy(update={"telem_baud": 921600})  # SERIAL1_BAUD 921: the download in ~1.5 s
    t0 = run_endpoints(tmp_path, gspec, uspec, relay)

    up = parse_each(relay.up)
    types = Counter(m.get_type() for _, m in up)
    assert len(types) >= 20
    assert set(types) >= set(streams.STREAMED) | {"HEARTBEAT", "TERRAIN_REQUEST", "PARAM_VALUE"}
    first = min(t for t, m in up if m.get_type() == "ATTITUDE")
    span = t0 + p.duration_s - first
    streamed = sum(n for typ, n in types.items() if typ in streams.STREAMED)
    assert streamed / span == pytest.approx(25 * 3, rel=0.1)
    glog = mv.read_log(gspec.log_path)
    done = [e for e in glog if e["event"] == "params"]
    assert len(done) == 1 and done[0]["count"] == 1095 and done[0]["lists"] == 1
    assert done[0]["reads"] >= len(relay.dropped_up) > 0  # every lost one asked for with PARAM_REQUEST_READ
    reads = [m for _, m in parse_each(relay.down) if m.get_type() == "PARAM_REQUEST_READ"]
    assert {m.param_index for m in reads} >= {m.param_index for _, m in parse_each([(0, d) for d in relay.dropped_up])}
    summary = [e for e in glog if e["event"] == "summary"][0]
    assert summary["params"] == {"uav0": 1095}
    # the attitude on the wire is the flight model's of the track at its time_boot_ms
    track = Track.of(p, "uav0")
    for _, m in up:
        if m.get_type() == "ATTITUDE":
            want = _state(track, m.time_boot_ms / 1000)
            assert (m.roll, m.pitch) == pytest.approx((want.roll_rad, want.pitch_rad), abs=1e-4)
            assert math.degrees(m.yaw) % 360 == pytest.approx(track.at(m.time_boot_ms / 1000).heading_deg, abs=1e-3)


@pytest.mark.slow  # three CLI processes loading uavcas
@pytest.mark.parametrize("args, why", [
    (["benign-6-2-telemetry-logdist-adaptive-random-30-95", "--stream-hz", "0"], "--stream-hz:"),
    (["benign-6-2-telemetry-logdist-adaptive-random-30-95", "--stream-hz", "51"], "--stream-hz:"),
    (["benign-6-2-image-logdist-adaptive-random-30-95", "--stream-hz", "3"],
     "--stream-hz: payload 'image' carries no MAVLink"),
])
def test_run_refuses_a_bad_stream_rate_in_one_line(tmp_path, args, why):
    import subprocess
    import sys

    r = subprocess.run([sys.executable, "-m", "uavcas", "run", *args, "--out", str(tmp_path / "run")],
                       capture_output=True, text=True, timeout=120)
    assert r.returncode == 2 and why in r.stderr, r.stderr
    assert len(r.stderr.strip().splitlines()) == 1 and not (tmp_path / "run").exists()
