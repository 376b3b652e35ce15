"""The autopilot endpoint's radio over loopback UDP: a pymavlink listener in the GCS's place hears
one RADIO_STATUS per second from SiK's ids, after each heartbeat, with the planned values."""

from __future__ import annotations

import select
import socket
import subprocess
import sys
import time

import pytest
from pymavlink.dialects.v20 import ardupilotmega

from uavcas.traffic import mavlink as mv
from uavcas.traffic.mavlink import radio as R
from uavcas.twin.plan import plan

pytestmark = pytest.mark.slow
CFG = "benign-5-2-mixed-logdist-adaptive-random-30-95"


def test_the_autopilot_sends_the_planned_radio_status_at_1_hz(tmp_path):
    p = plan(CFG, seed=0, windows=3, window_s=2.0)
    listener = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    listener.bind(("127.0.0.1", 0))
    dur = p.duration_s + 0.5
    uspec = mv.uav_spec(p, "uav0", "127.0.0.1", None, dur, tmp_path / "uav0.jsonl",
                        gcs_port=listener.getsockname()[1], bind_port=0, t0_path=tmp_path / "t0")
    assert uspec.radio is not None and len(uspec.radio.reports) == 6
    (tmp_path / "u.json").write_text(uspec.model_dump_json())
    proc = subprocess.Popen([sys.executable, "-m", "uavcas.traffic.mavlink", "uav", str(tmp_path / "u.json")],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    got = []  # (arrival time, message) of every frame, in order
    try:
        assert proc.stdout.readline().strip() == "ready"
        t0 = time.time()
        mv.write_t0(uspec.t0_path, t0)
        mav = ardupilotmega.MAVLink(None)  # strict: a bad frame raises
        while time.time() < t0 + dur + 1.0:
            r, _, _ = select.select([listener], [], [], 0.1)
            if r:
                data, _ = listener.recvfrom(65535)
                got += [(time.time(), m) for m in mav.parse_buffer(data) or []]
        _, err = proc.communicate(timeout=10)
        assert proc.returncode == 0, err[-1000:]
    finally:
        proc.kill()
        listener.close()

    radio = [(t, m) for t, m in got if m.get_type() == "RADIO_STATUS"]
    assert all((m.get_srcSystem(), m.get_srcComponent()) == (R.SIK_SYSID, R.SIK_COMPID) for _, m in radio)
    # one per heartbeat, right after it: 1 Hz from t0 until the deadline
    beats = [t for t, m in got if m.get_type() == "HEARTBEAT"]
    assert len(radio) == len(beats) and len(radio) in (6, 7)
    gaps = [b - a for (a, _), (b, _) in zip(radio, radio[1:])]
    assert all(0.8 < g < 1.2 for g in gaps), gaps
    assert all(0 <= tr - tb < 0.1 for tb, (tr, _) in zip(beats, radio))
    # the k-th report carries the plan's values of second k (the last repeats past the plan)
    for k, (_, m) in enumerate(radio):
        want = uspec.radio.reports[min(k, len(uspec.radio.reports) - 1)]
        assert (m.rssi, m.remrssi, m.txbuf, m.noise, m.remnoise, m.rxerrors, m.fixed) == (
            want.rssi, want.remrssi, want.txbuf, want.noise, want.remnoise, want.rxerrors, want.fixed), k
    # the radio counts its own sequence numbers, as SiK's mavlink.c does
    assert [m.get_seq() for _, m in radio] == list(range(len(radio)))
    summary = [e for e in mv.read_log(uspec.log_path) if e["event"] == "summary"][0]
    assert summary["radio_sent"] == {"RADIO_STATUS": len(radio)}
