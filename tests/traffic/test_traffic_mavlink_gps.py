"""The GPS receiver model (traffic/mavlink/gps.py): the spoofer's offset, the control file, the timing rule.

Hand-computed cases: bearing 30 degrees, 3 m/s, so after 10 s the offset is 30 m along the
bearing: east 30 sin 30 = 15 m, north 30 cos 30 = 25.981 m.
"""

from __future__ import annotations

import math
import time

import pytest

from uavcas.traffic.mavlink.gps import (
    Spoofing,
    claimed,
    control_path,
    course_deg,
)
from uavcas.twin.track import Track, TrackPoint

T = 1_700_000_000.0
SPOOF = Spoofing(start_unix=T, stop_unix=T + 20, drift_mps=3.0, bearing_deg=30.0, distance_m=45.0)


def test_offset_grows_at_the_drift_rate_towards_the_lure():
    e, n, u = SPOOF.offset_m(T + 10)
    assert (e, n, u) == pytest.approx((15.0, 25.980762, 0.0), abs=1e-6)
    assert math.hypot(e, n) == pytest.approx(30.0) and u == 0.0
    assert SPOOF.offset_m(T) == (0.0, 0.0, 0.0)  # carry-off starts aligned: no jump
    assert SPOOF.drift_velocity_mps(T + 10) == pytest.approx((1.5, 2.598076, 0.0), abs=1e-6)


def test_offset_holds_at_the_lure_and_vanishes_outside_the_window():
    assert math.hypot(*SPOOF.offset_m(T + 15)[:2]) == pytest.approx(45.0)  # 3 m/s x 15 s = 45 m: there
    assert math.hypot(*SPOOF.offset_m(T + 19.9)[:2]) == pytest.approx(45.0)  # and it stays
    assert SPOOF.drift_velocity_mps(T + 16) == (0.0, 0.0, 0.0)
    assert SPOOF.offset_m(T - 0.001) == (0.0, 0.0, 0.0)
    assert SPOOF.offset_m(T + 20) == (0.0, 0.0, 0.0)  # stop is exclusive: the true signal is back
    running = SPOOF.model_copy(update={"stop_unix": None})
    assert math.hypot(*running.offset_m(T + 1e4)[:2]) == pytest.approx(45.0)


def test_claimed_point_and_course():
    p = TrackPoint(5.0, 100.0, 200.0, 50.0, 0.0, 4.0, 0.5, 0.0)  # flying north at 4 m/s, climbing
    q = claimed(p, SPOOF, T + 10)
    assert (q.x_m, q.y_m, q.z_m) == pytest.approx((115.0, 225.980762, 50.0))
    assert (q.vx_mps, q.vy_mps, q.vz_mps) == pytest.approx((1.5, 6.598076, 0.5))
    assert q.heading_deg == 0.0  # the compass's heading, not the receiver's
    assert course_deg(q) == pytest.approx(math.degrees(math.atan2(1.5, 6.598076)))
    assert claimed(p, SPOOF, T + 25) is p and claimed(p, None, T + 10) is p
    rest = TrackPoint(0.0, 0, 0, 0, 0, 0, 0, 123.0)
    assert course_deg(rest) == 123.0  # at rest: the last move's heading, as the track defines it


@pytest.mark.slow
def test_autopilot_reports_the_spoofers_drift_between_the_logged_times(tmp_path):
    """The real endpoints on 127.0.0.1 (as test_mavlink_units), the real executor publishing the
    plan's gps_spoof attack mid-run: the reports decided inside the logged [start, stop) carry the
    drift, the others the track, and the autopilot counts them."""
    from helpers.mavlink_relay import Relay, free_port, parse_each, run_endpoints
    from uavcas.emulation.attacks import AttackExecutor
    from uavcas.traffic import mavlink as mv
    from uavcas.twin.plan import plan
    from uavcas.twin.track import geodetic_to_local

    p = plan("gps_spoof=5-6-2-telemetry-logdist-adaptive-random-30-95", seed=14, windows=4, window_s=1.5)
    (att,) = p.attacks
    att = att.model_copy(update={"start_s": 2.0, "stop_s": 4.0})  # inside the 6 s run, after the streams start
    victim = att.victims[0]
    gcs_port = free_port()
    relay = Relay(gcs_port, drop_once=())
    relay.start()
    dur, t0_path, apps = p.duration_s + 0.5, tmp_path / "t0", tmp_path / "apps"
    gspec = mv.GcsSpec(name="bs0", sysid=p.node("bs0").sysid, bind_ip="127.0.0.1", port=gcs_port,
                       uavs=[mv.gcs_target(p, victim)], t0_path=t0_path, window_s=p.window_s, n_windows=4,
                       duration_s=dur, log_path=tmp_path / "mavlink-bs0.jsonl")
    uspec = mv.uav_spec(p, victim, "127.0.0.1", None, dur, tmp_path / "mavlink-uav.jsonl", gcs_port=relay.port,
                        t0_path=t0_path, gps_path=control_path(apps, victim))
    ex = AttackExecutor(None, p, apps, p.duration_s)
    times: dict[str, float] = {}

    def attack(t0: float) -> None:  # the runner's schedule, in short
        time.sleep(max(0.0, t0 + att.start_s - time.time()))
        times["start"] = ex.start(att).t_unix
        time.sleep(max(0.0, t0 + att.stop_s - time.time()))
        times["stop"] = ex.stop(att).t_unix

    t0 = run_endpoints(tmp_path, gspec, uspec, relay, attack)
    start, stop = times["start"], times["stop"]

    b, inside, outside = math.radians(att.params["lure_bearing_deg"]), 0, 0
    track = Track.of(p, victim)
    for _, m in parse_each(relay.up):
        if m.get_type() == "LOCAL_POSITION_NED":  # no spoofed position outside the labelled messages
            q = track.at(m.time_boot_ms / 1000)
            assert abs(m.x - q.y_m) < 0.01 and abs(m.y - q.x_m) < 0.01, (m, q)
        if m.get_type() not in ("GLOBAL_POSITION_INT", "GPS_RAW_INT"):
            continue
        ms = m.time_boot_ms if m.get_type() == "GLOBAL_POSITION_INT" else m.time_usec / 1000
        t = t0 + ms / 1000
        x, y, _ = geodetic_to_local(p.site, m.lat / 1e7, m.lon / 1e7, m.alt / 1000)
        q = track.at(ms / 1000)
        spoofed = start <= t < stop
        d = min(5.0 * (t - start), att.params["lure_distance_m"]) if spoofed else 0.0
        assert abs(x - q.x_m - d * math.sin(b)) < 0.05 and abs(y - q.y_m - d * math.cos(b)) < 0.05, (t - t0, d)
        inside, outside = inside + spoofed, outside + (not spoofed)
    assert inside >= 2 * 4 * 1.5 and outside >= 2 * 4 * 1.5  # both reports at 4 Hz, >= 1.5 s each side
    summary = next(e for e in mv.read_log(uspec.log_path) if e["event"] == "summary")
    assert summary["gps"] == {"spoofed": inside, "straddled": 0}
