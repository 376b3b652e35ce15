"""Real runs of MAVLink command injection (issue 24): 6 UAVs, 2 BSs, 4 windows, payload
`telemetry`, one attacker UAV forging RTL to the victim's autopilot, once with the endpoints'
MAVLink 2 signing off and once with it on (`--mavlink-signing`), same scenario and seed.

Checks, from the runs' logs, their captures decoded by `uavcas mavlink` and their extraction:
without signing every forged command is acknowledged (the injector's count and the victim's
COMMAND_ACKs on the wire, labelled `provoked`), and the victim's HEARTBEATs switch from AUTO (3)
to RTL (6) once the first forged frame reached it; with signing none is acknowledged, the
HEARTBEATs stay AUTO, the forged frames keep their `mavlink_inject` label and the ground
stations' signed commands are still acknowledged. Both audits pass, and every flow labelled
MAVLinkInjection holds an affected packet. Run under the root lock:
  flock /tmp/uavcas-root.lock pytest tests/emulation/test_mavlink_inject_root.py
"""

from __future__ import annotations

import json

import pytest

from helpers.audit_checks import assert_audit_passes
from uavcas.rundir import RunDir
from uavcas.testing.audited import run_audited
from uavcas.traffic.mavlink import read_log

pytestmark = [pytest.mark.root, pytest.mark.slow]
CFG = "mavlink_inject=rtl-6-2-telemetry-logdist-adaptive-random-30-95"
SEED = 14  # victim uav5, attacker uav3 one hop from it in every window, attack [3.7, 16.6) s


@pytest.fixture(scope="module")
def runs(tmp_path_factory) -> dict[bool, RunDir]:
    base = tmp_path_factory.mktemp("inject")
    out = {}
    for signed in (False, True):  # one after the other: two emulations at once break the audit's tolerances
        d = base / ("on" if signed else "off")
        signing = ["--mavlink-signing"] if signed else []
        out[signed] = RunDir(run_audited([CFG, "--seed", str(SEED), "--windows", "4", *signing], d, timeout_s=240))
    return out


def _attack(run: RunDir):
    recs = [json.loads(line) for line in run.attacks_jsonl.read_text().splitlines()]
    start = next(r for r in recs if r["event"] == "start")
    stop = next(r for r in recs if r["event"] == "stop")
    return start, stop


def _decoded(run: RunDir, start: dict):
    """The MAVLink tables at the attacker's and at the victim's switch, the victim's HEARTBEAT
    times and custom_modes, and the forged COMMAND_LONGs seen at each switch."""
    from uavcas.mavlink_capture import mavlink_table

    t = mavlink_table(run.root)
    assert t.crc_ok.fillna(False).all()
    (victim,), (ip,), (xip,) = start["victims"], start["victim_ips"], start["attacker_ips"]
    at_x, at_v = t[t.point == f"s-{start['attackers'][0]}"], t[t.point == f"s-{victim}"]
    beats = at_v[(at_v.msg_name == "HEARTBEAT") & (at_v.src_ip == ip)]
    modes = beats.fields_json.map(lambda s: json.loads(s)["custom_mode"]).to_numpy()
    forged = [a[(a.msg_name == "COMMAND_LONG") & (a.src_ip == xip)] for a in (at_x, at_v)]
    return t, at_v, beats.ts_s.to_numpy(), modes, forged


@pytest.mark.parametrize("signed", [False, True])
def test_runs_are_faithful_and_record_signing(runs, signed):
    info = runs[signed].read_info()
    assert info.exit_status == 0 and info.mavlink_signing is signed
    assert_audit_passes(runs[signed])


def test_without_signing_the_forged_rtl_is_acknowledged_and_the_mode_changes(runs):
    run = runs[False]
    start, stop = _attack(run)
    assert stop["commands_sent"] >= 20 and stop["commands_acked"] >= 0.8 * stop["commands_sent"]
    t, at_v, ts, modes, (sent, arrived) = _decoded(run, start)
    assert len(sent) == stop["commands_sent"]  # every frame the injector logged left its switch
    # what the injector received is what reached its switch (the shaped links may lose some)
    back = t[(t.point == f"s-{start['attackers'][0]}") & (t.msg_name == "COMMAND_ACK")
             & (t.src_ip == start["victim_ips"][0]) & (t.dst_ip == start["attacker_ips"][0])]
    assert len(back) == stop["commands_acked"]
    assert (t[(t.msg_name == "COMMAND_LONG") & (t.src_ip == start["attacker_ips"][0])].effect == "mavlink_inject").all()
    # every forged frame that reached the victim is answered: its COMMAND_ACK, provoked by the injection
    acks = at_v[(at_v.msg_name == "COMMAND_ACK") & (at_v.src_ip == start["victim_ips"][0])
                & (at_v.dst_ip == start["attacker_ips"][0])]
    assert len(arrived) >= 20 and len(acks) == len(arrived)
    assert (acks.effect == "provoked").all() and (acks.family == "mavlink_inject").all()
    first = arrived.ts_s.min()
    assert set(modes[ts < first]) == {3}  # AUTO before
    assert set(modes[ts > first + 0.01]) == {6}  # RTL from the first forged frame on
    assert (ts > first + 0.01).sum() >= 10


def test_with_signing_the_forged_rtl_is_dropped_but_keeps_its_label(runs):
    run = runs[True]
    start, stop = _attack(run)
    assert stop["commands_sent"] >= 20 and stop["commands_acked"] == 0
    t, at_v, ts, modes, (sent, arrived) = _decoded(run, start)
    assert len(sent) == stop["commands_sent"] and len(arrived) >= 20
    assert (t[(t.msg_name == "COMMAND_LONG") & (t.src_ip == start["attacker_ips"][0])].effect == "mavlink_inject").all()
    assert not ((t.src_ip == start["victim_ips"][0]) & (t.dst_ip == start["attacker_ips"][0])).any()  # no answer
    assert not (t.effect == "provoked").any()
    assert set(modes) == {3} and len(modes) >= 15
    ulog = read_log(run.logs_dir / f"mavlink-{start['victims'][0]}.jsonl")
    assert sum(e["event"] == "rejected" for e in ulog) == len(arrived)
    # the ground stations' signed exchange still works: every window's command acknowledged
    plan = run.read_plan()
    for bs in (n.name for n in plan.nodes if n.kind == "bs"):
        glog = read_log(run.logs_dir / f"mavlink-{bs}.jsonl")
        results = [e["result"] for e in glog if e["event"] == "command_result"]
        assert results and set(results) == {"accepted"}, (bs, results)


@pytest.mark.parametrize("signed", [False, True])
def test_every_injection_flow_holds_a_forged_packet(runs, signed):
    from uavcas.extract import extract

    shard = extract(runs[signed].root)
    df = shard.frame
    inj = df[df.label == "MAVLinkInjection"]
    assert len(inj) >= 1 and (inj.attack_packets_mavlink_inject > 0).all()
    assert (df[df.label != "MAVLinkInjection"].attack_packets_mavlink_inject == 0).all()
    if signed:  # no answer to a rejected frame: nothing provoked
        assert (inj.provoked_packets == 0).all()
    else:  # the acks travel in the forged frames' flow (the same UDP 5-tuple, reversed)
        assert (inj.provoked_packets > 0).all()
