"""The GPS receiver model (apps/mavlink/gps.py): the spoofer's offset, the control file, the timing rule.

Hand-computed cases: bearing 30 degrees, 3 m/s, so after 10 s the offset is 30 m along the
bearing: east 30 sin 30 = 15 m, north 30 cos 30 = 25.981 m.
"""

from __future__ import annotations

import math
import threading
import time

import pytest

from uavcas.emulation.apps.mavlink.gps import (GUARD_S, LEAD_S, GpsReceiver, Spoofing, claimed, control_path,
                                               course_deg, publish)
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


def test_publish_writes_atomically_ahead_and_the_receiver_reads_it(tmp_path):
    paths = [control_path(tmp_path, "uav2"), control_path(tmp_path, "uav3")]
    assert paths[0] == tmp_path / "mavlink" / "gps-uav2.json"
    before = time.time()
    t = publish(paths, lambda s: SPOOF.model_copy(update={"start_unix": s, "stop_unix": None}))
    assert before + LEAD_S <= t <= time.time() + LEAD_S and time.time() <= t - GUARD_S
    rx = GpsReceiver(paths[1])
    rx.poll()
    assert rx.spoof is not None and rx.spoof.start_unix == t and rx.spoof.stop_unix is None
    assert not list(tmp_path.glob("mavlink/*.tmp"))
    assert GpsReceiver(tmp_path / "absent.json").settle() <= time.time()  # no spoofer: true fixes


def test_a_fix_due_just_before_a_boundary_waits_for_it(tmp_path):
    path = control_path(tmp_path, "uav0")
    start = publish([path], lambda s: SPOOF.model_copy(update={"start_unix": s, "stop_unix": None}))
    rx = GpsReceiver(path)
    time.sleep(max(0.0, start - GUARD_S / 2 - time.time()))  # now inside the guard before start
    t = rx.settle()
    assert t >= start and rx.spoof.active(t)
    track = Track((0.0, 100.0), ((0.0, 0.0, 50.0), (0.0, 400.0, 50.0)))  # 4 m/s north
    sent = []
    rx.report(track, start - 10.0, lambda fix, t_plan: sent.append((fix, t_plan)))
    (fix, t_plan), = sent
    assert fix.y_m - 4.0 * t_plan == pytest.approx(3.0 * (t_plan - 10.0) * math.cos(math.radians(30)), abs=1e-6)
    assert rx.summary() == {"spoofed": 1, "straddled": 0}


def test_a_late_send_is_counted_as_straddling(tmp_path):
    path = control_path(tmp_path, "uav0")
    start = publish([path], lambda s: SPOOF.model_copy(update={"start_unix": s, "stop_unix": None}))
    rx = GpsReceiver(path)
    track = Track((0.0,), ((0.0, 0.0, 50.0),))
    # decided well before the start, sent after it (a send stuck for 2 LEAD_S): the run's log says so
    rx.report(track, start, lambda fix, t_plan: time.sleep(2 * LEAD_S))
    assert rx.summary() == {"spoofed": 0, "straddled": 1}


def test_the_stop_is_seen_by_a_receiver_polling_meanwhile(tmp_path):
    path = control_path(tmp_path, "uav0")
    start = publish([path], lambda s: SPOOF.model_copy(update={"start_unix": s, "stop_unix": None}))
    rx = GpsReceiver(path)
    stop: list[float] = []
    th = threading.Thread(target=lambda: stop.append(
        publish([path], lambda s: SPOOF.model_copy(update={"start_unix": start, "stop_unix": s}))))
    th.start()
    th.join()
    time.sleep(max(0.0, stop[0] - time.time()))
    t = rx.settle()
    assert rx.spoof.stop_unix == stop[0] and t >= stop[0] and not rx.spoof.active(t)
