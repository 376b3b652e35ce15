"""Forged MAVLink commands against the real endpoints over 127.0.0.1 (no namespaces, no root).

A ground station, an autopilot and the attacker's injector (`attacks/tools/mavinject.py`) run as three
processes; a relay between autopilot and GCS (the MAVLink unit test's) records the autopilot's
frames, so the HEARTBEATs on the wire show the mode. Without signing the forged RTL is accepted,
acknowledged to the injector and the mode becomes RTL (6); with signing (the run's key on GCS and
UAV, none for the injector) it is dropped unanswered while the GCS's signed exchange goes on.
"""

from __future__ import annotations

import subprocess
import sys
import time

import pytest

from helpers.mavlink_relay import Relay, free_port, stop_all, wait_all
from uavcas.attacks.tools import tool_path
from uavcas.attacks.tools.mavinject import read_log as read_injector_log
from uavcas.traffic import mavlink as mv
from uavcas.traffic.mavlink.commands import COPTER_MODE_RTL
from uavcas.traffic.mavlink.specs import COPTER_MODE_AUTO
from uavcas.twin.plan import plan

pytestmark = pytest.mark.slow
CFG = "mavlink_inject=rtl-6-2-telemetry-logdist-adaptive-random-30-95"
FORGED = 3
GO_AFTER_S = 1.2  # the injector starts after the mission upload and the first heartbeats


def _frames(datagrams, key: bytes | None = None):
    from pymavlink.dialects.v20 import ardupilotmega as common  # the dialect the endpoints speak

    out = []
    for t, d in datagrams:
        mav = common.MAVLink(None)
        if key is not None:  # check every signature with the run's key
            mav.signing.secret_key = key
            # but the UAV radio's RADIO_STATUS, unsigned as SiK's is, accepted as ArduPilot does
            mav.signing.allow_unsigned_callback = lambda _, msg_id: msg_id == common.MAVLINK_MSG_ID_RADIO_STATUS
        msgs = mav.parse_buffer(d)
        assert msgs is not None and len(msgs) == 1 and msgs[0].get_type() != "BAD_DATA", d
        out.append((t, msgs[0], mav.signing.goodsig_count))
    return out


@pytest.mark.parametrize("signed", [False, True])
def test_forged_rtl_is_accepted_without_signing_and_dropped_with_it(tmp_path, signed):
    p = plan(CFG, seed=5, windows=3, window_s=1.5)
    victim, bs = p.attacks[0].victims[0], "bs0"
    key = mv.signing_spec(p.seed, p.config) if signed else None
    gcs_port, uav_port = free_port(), free_port()
    relay = Relay(gcs_port, drop_once=())
    relay.start()
    dur, t0_path = p.duration_s + 0.5, tmp_path / "t0"
    gspec = mv.GcsSpec(name=bs, sysid=p.node(bs).sysid, bind_ip="127.0.0.1", port=gcs_port, signing=key,
                       uavs=[mv.gcs_target(p, victim)], t0_path=t0_path, window_s=p.window_s, n_windows=3,
                       duration_s=dur, log_path=tmp_path / "gcs.jsonl")
    uspec = mv.uav_spec(p, victim, "127.0.0.1", None, dur, tmp_path / "uav.jsonl", gcs_port=relay.port,
                        bind_ip="127.0.0.1", bind_port=uav_port, t0_path=t0_path, signing=key)
    (tmp_path / "g.json").write_text(gspec.model_dump_json())
    (tmp_path / "u.json").write_text(uspec.model_dump_json())
    go, ilog = tmp_path / "go", tmp_path / "inject.jsonl"
    run = [sys.executable, "-m", "uavcas.traffic.mavlink"]
    inject = [sys.executable, str(tool_path("mavinject")), "--victim-ip", "127.0.0.1", "--port",
              str(uav_port), "--target-sysid", str(p.node(victim).sysid), "--gcs-sysid", str(p.node(bs).sysid),
              "--command", "rtl", "--rate-hz", "4", "--count", str(FORGED), "--go", str(go), "--log", str(ilog),
              "--seconds", str(dur + 20)]
    procs = [subprocess.Popen(argv, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
             for argv in (run + ["gcs", str(tmp_path / "g.json")], run + ["uav", str(tmp_path / "u.json")], inject)]
    try:
        assert [proc.stdout.readline().strip() for proc in procs] == ["ready"] * 3
        t0 = time.time()
        mv.write_t0(t0_path, t0)
        time.sleep(GO_AFTER_S)
        t_go = time.time()
        go.touch()
        wait_all(procs, dur + 20)
    finally:
        stop_all(relay, procs)

    sent, acks = read_injector_log(ilog)
    ulog, glog = mv.read_log(uspec.log_path), mv.read_log(gspec.log_path)
    forged = [e for e in ulog if e["event"] == "command" and e["command"] == 20]  # MAV_CMD_NAV_RETURN_TO_LAUNCH
    rejected = [e for e in ulog if e["event"] == "rejected"]
    up = _frames(relay.up, key.key if key else None)
    beats = [(t, m.custom_mode) for t, m, _ in up if m.get_type() == "HEARTBEAT"]
    assert sent == FORGED
    if not signed:
        assert acks == FORGED and len(forged) == FORGED and not rejected
        assert all(e["result"] == 0 and e["mode"] == COPTER_MODE_RTL for e in forged)  # MAV_RESULT_ACCEPTED
        assert {m for t, m in beats if t < t_go} == {COPTER_MODE_AUTO}
        t_first = t0 + forged[0]["t_s"]
        after = [m for t, m in beats if t > t_first + 0.01]
        assert after and set(after) == {COPTER_MODE_RTL}  # the HEARTBEAT shows the commanded mode
    else:
        assert acks == 0 and not forged and len(rejected) == FORGED
        assert all("signature" in e["reason"] for e in rejected)
        assert {m for _, m in beats} == {COPTER_MODE_AUTO}
        # every frame of the autopilot carries a valid signature; its radio's reports none (radio.py)
        assert all(good == (m.get_type() != "RADIO_STATUS") for _, m, good in up)
        assert any(m.get_type() == "RADIO_STATUS" for _, m, _ in up)
    # the legitimate exchange works either way: mission uploaded, every window's command acknowledged
    assert [e["result"] for e in glog if e["event"] == "mission_upload"] == ["accepted"]
    assert {e["window"]: e["result"] for e in glog if e["event"] == "command_result"} == {1: "accepted", 2: "accepted"}


def test_a_command_signed_with_another_key_is_rejected():
    """Wrongly signed = unsigned for the autopilot: pymavlink's check fails, the frame is BAD_DATA."""
    from pymavlink.dialects.v20 import common as m

    from uavcas.traffic.mavlink.signing import SigningSpec, new_signing_state

    run_key, other = mv.signing_spec(1, "cfg-a"), SigningSpec(key_hex="ab" * 32)
    out = []

    class Buf:
        def write(self, b):
            out.append(bytes(b))

    for spec in (other, run_key):
        tx = m.MAVLink(Buf(), srcSystem=255, srcComponent=190)
        tx.signing = new_signing_state(spec)
        tx.send(m.MAVLink_command_long_message(1, 1, m.MAV_CMD_NAV_LAND, 0, 0, 0, 0, 0, 0, 0, 0))
    rx = m.MAVLink(None)
    rx.robust_parsing = True
    rx.signing = new_signing_state(run_key)
    wrong, right = (rx.parse_buffer(d)[0] for d in out)
    assert wrong.get_type() == "BAD_DATA" and "signature" in wrong.reason
    assert right.get_type() == "COMMAND_LONG" and right.command == m.MAV_CMD_NAV_LAND
    # RADIO_STATUS is the one message accepted unsigned (ArduPilot's rule)
    plain = m.MAVLink(Buf(), srcSystem=51, srcComponent=68)
    plain.send(m.MAVLink_radio_status_message(200, 180, 100, 10, 10, 0, 0))
    assert rx.parse_buffer(out[-1])[0].get_type() == "RADIO_STATUS"


def test_the_injector_refuses_a_bad_rate_in_one_line(tmp_path):
    r = subprocess.run([sys.executable, str(tool_path("mavinject")), "--victim-ip", "127.0.0.1",
                        "--target-sysid", "1", "--gcs-sysid", "255", "--command", "rtl", "--rate-hz", "0",
                        "--go", str(tmp_path / "go"), "--log", str(tmp_path / "l"), "--seconds", "1"],
                       capture_output=True, text=True, timeout=60)
    assert r.returncode == 2 and len(r.stderr.strip().splitlines()) == 1

