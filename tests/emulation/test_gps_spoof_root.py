"""A real run of the GPS spoofing family (issue 24): 6 UAVs, 2 BSs, 6 windows, payload `telemetry`.

Checks, from the run's captures, attack log and endpoint logs: the victim's position reports
(GLOBAL_POSITION_INT, GPS_RAW_INT), decoded by `uavcas mavlink`'s table, drift from the plan's
track by drift_mps * (t - start) along the lure's bearing within 1 m inside the logged [start,
stop) (t: the message's own time_boot_ms) and not at all outside it, nor for any other UAV; the
truth labels `gps_spoof` exactly those messages (every observation), and no other packet; the
autopilot saw no report straddle a boundary; the fidelity audit passes; and every flow labelled
GPSSpoofing holds a gps_spoof packet.
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from helpers.audit_checks import assert_audit_passes
from uavcas.events import AttackStart, AttackStop, read_attack_records
from uavcas.rundir import RunDir
from uavcas.testing.audited import run_audited
from uavcas.traffic.mavlink import read_log

pytestmark = [pytest.mark.root, pytest.mark.slow]
CFG = "gps_spoof=3-6-2-telemetry-logdist-adaptive-random-30-95"
SEED = 14
REPORTS = ("GLOBAL_POSITION_INT", "GPS_RAW_INT")


@pytest.fixture(scope="module")
def run(tmp_path_factory) -> RunDir:
    out = tmp_path_factory.mktemp("gps") / "run"
    return RunDir(run_audited([CFG, "--seed", str(SEED), "--windows", "6"], out, timeout_s=300))


@pytest.fixture(scope="module")
def window(run):
    (att,) = run.read_plan().attacks
    recs = read_attack_records(run.attacks_jsonl)
    start = next(r.t_unix for r in recs if isinstance(r, AttackStart))
    stop = next(r.t_unix for r in recs if isinstance(r, AttackStop))
    return att, start, stop


@pytest.fixture(scope="module")
def table(run):
    from uavcas.mavlink_capture import mavlink_table

    return mavlink_table(run.root)


def test_run_and_audit_pass(run):
    info = run.read_info()
    assert info.exit_status == 0
    assert_audit_passes(run)


def test_victim_reports_drift_at_the_rate_towards_the_lure_inside_the_window(run, window, table):
    att, start, stop = window
    plan, t0 = run.read_plan(), run.read_info().t0_unix
    victim = plan.node(att.victims[0])
    good = table[table["crc_ok"].fillna(False).astype(bool) & table["msg_name"].isin(REPORTS)]
    mine = good[good["sysid"] == victim.sysid]
    t = t0 + np.array([_boot_s(f) for f in mine["fields_json"]])
    inside = (t >= start) & (t < stop)
    assert inside.sum() >= 2 * 4 * 8  # both reports at 4 Hz for >= 8 s of the 10-20 s attack
    b = math.radians(att.params["lure_bearing_deg"])
    d = np.where(inside, np.minimum(att.params["drift_mps"] * (t - start), att.params["lure_distance_m"]), 0.0)
    err = np.hypot(mine["offset_east_m"] - d * math.sin(b), mine["offset_north_m"] - d * math.cos(b))
    assert err.max() < 1.0 and np.abs(mine["offset_up_m"]).max() < 0.01
    assert d.max() > 20.0  # it really drifted (3 m/s over >= 8 s)
    others = good[good["sysid"] != victim.sysid]
    assert len(others) and np.hypot(others["offset_east_m"], others["offset_north_m"]).max() < 0.05
    summary = next(e for e in read_log(run.logs_dir / f"mavlink-{victim.name}.jsonl") if e["event"] == "summary")
    at_own_switch = (mine["point"] == f"s-{victim.name}").to_numpy()  # every report the victim sent, once
    assert summary["gps"]["straddled"] == 0 and summary["gps"]["spoofed"] == int((inside & at_own_switch).sum())


def test_truth_labels_exactly_the_spoofed_reports(run, window, table):
    from uavcas.mavlink_capture import run_packets
    from uavcas.vocabulary import EFFECTS

    att, start, stop = window
    plan, t0 = run.read_plan(), run.read_info().t0_unix
    victim = plan.node(att.victims[0])
    t = t0 + np.array([_boot_s(f) if isinstance(f, str) else -1.0 for f in table["fields_json"]])
    spoofed = ((table["sysid"] == victim.sysid).fillna(False).to_numpy() & table["msg_name"].isin(REPORTS).to_numpy()
               & (t >= start) & (t < stop))
    assert spoofed.sum() > 0
    assert ((table["effect"] == "gps_spoof").to_numpy() == spoofed).all()  # every observation, nothing else
    rp = run_packets(run.root)
    hit = rp.effect == EFFECTS.index("gps_spoof")
    assert int(hit.sum()) == int(spoofed.sum())  # no packet outside the MAVLink table carries the effect
    assert np.isin(rp.packets["mav_msgid"][hit], (24, 33)).all()


def test_every_gps_spoofing_flow_holds_a_spoofed_report(run):
    from uavcas.extract import extract

    frame = extract(run.root).frame
    labelled = frame[frame["label"] == "GPSSpoofing"]
    assert len(labelled) >= 1
    assert (labelled["attack_packets_gps_spoof"] > 0).all()
    assert set(frame["label"]) <= {"Benign", "GPSSpoofing"}


def _boot_s(fields_json: str) -> float:
    f = json.loads(fields_json)
    return f["time_boot_ms"] / 1000 if "time_boot_ms" in f else f.get("time_usec", -1e9) / 1e6

