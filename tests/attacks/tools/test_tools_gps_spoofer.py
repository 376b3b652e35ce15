"""The GPS spoofer (`attacks/tools/gps_spoofer.py`) against the receiver it fools
(`traffic/mavlink/gps.py`): published ahead, atomically, and the boundaries agree."""

from __future__ import annotations

import math
import threading
import time

import pytest

from uavcas.attacks.tools.gps_spoofer import LEAD_S, publish
from uavcas.traffic.mavlink.gps import GUARD_S, GpsReceiver, Spoofing, control_path
from uavcas.twin.track import Track

T = 1_700_000_000.0
SPOOF = Spoofing(start_unix=T, stop_unix=T + 20, drift_mps=3.0, bearing_deg=30.0, distance_m=45.0)


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

