"""Labels on the synthetic run: packet-exact floods and replays, victim windows, paper option."""

from __future__ import annotations

import json

import pytest
from synth_run import BLACKHOLE_WINDOW, DOS_WINDOW, IPS, N_FLOOD, T0, make_plan

from uavcas.events import AttackStart, AttackStop, attack_log_text
from uavcas.flows import extract_flows
from uavcas.labels import LabelError, label_flows, read_attack_log
from uavcas.rundir import RunDir
from uavcas.schema import LABEL_COLUMNS
from uavcas.twin.model import Plan


def _labelled(run_dir, mode="ours", view="5tuple"):
    from uavcas.flows import FlowConfig

    pcaps = sorted((run_dir / "pcap").glob("*.pcap"))
    ex = extract_flows(pcaps, FlowConfig(view=view))
    plan = Plan.from_json((run_dir / "plan.json").read_text())
    log = read_attack_log(run_dir / "attacks.jsonl", plan, T0)
    return label_flows(ex.packets, ex.flows, ex.frame, log, mode=mode)


def test_flood_flows_are_dos_only_inside_window(synth_run_dir):
    df = _labelled(synth_run_dir)
    pair = df[(df.src_ip == IPS["uav1"]) & (df.dst_ip == IPS["uav0"])]
    inside = pair[(pair.first_ts >= T0 + DOS_WINDOW[0]) & (pair.first_ts < T0 + DOS_WINDOW[1])]
    outside = pair.drop(inside.index)
    assert len(inside) == N_FLOOD and (inside.label == "DoS").all() and inside.label_dos.all()
    assert (inside.label_source == "flood-packets").all()
    # two sessions outside, each two flows (the server's FIN ends the first; flows.assemble rule 4a)
    assert outside.src_port.nunique() == 2 and len(outside) == 4
    assert (outside.label == "Benign").all() and (outside.label_source == "none").all()
    # the victim's other flows are not DoS
    assert not df[(df.src_ip == IPS["bs0"])].label_dos.any()


def test_replay_and_blackhole(synth_run_dir):
    df = _labelled(synth_run_dir)
    rep = df[df.label_replay]
    assert len(rep) == 1 and rep.iloc[0].src_port == 41001 and rep.iloc[0].label_source == "replay-injections"
    # the session's trailing FIN flow (2 packets) plus the three injected packets, 1.3 s later
    assert rep.iloc[0].packets == 2 + 3
    bh = df[df.label_blackhole]
    assert len(bh) == 2 and (bh.dst_ip == IPS["uav3"]).all() and (bh.label == "Blackhole").all()  # session + FIN tail
    assert T0 + BLACKHOLE_WINDOW[0] <= bh.iloc[0].first_ts < T0 + BLACKHOLE_WINDOW[1]
    counts = df.label.value_counts().to_dict()
    assert counts == {"DoS": N_FLOOD, "Benign": 25, "Replay": 1, "Blackhole": 2}
    assert set(LABEL_COLUMNS) <= set(df.columns)


def test_paper_ip_membership(synth_run_dir):
    df = _labelled(synth_run_dir, mode="paper")
    assert (df.label_source == "ip-membership").all()
    # no time gating: the benign uav1 -> uav0 sessions outside the window are DoS too
    pair = df[(df.src_ip == IPS["uav1"])]
    assert (pair.label == "DoS").all() and len(pair) == N_FLOOD + 2 * 2
    assert (df[df.dst_ip == IPS["uav3"]].label == "Blackhole+Replay").all()


def test_hostpair_view_labels(synth_run_dir):
    df = _labelled(synth_run_dir, view="hostpair")
    flood = df[(df.src_ip == IPS["uav1"]) | (df.dst_ip == IPS["uav1"])]
    assert len(flood) == 1 and flood.iloc[0].label == "DoS"


def test_plan_fallback_and_errors(tmp_path):
    plan = make_plan()
    log = read_attack_log(tmp_path / "absent.jsonl", plan, T0)
    dos = [w for w in log.windows if w.family == "dos"][0]
    assert dos.from_plan and dos.start_unix == T0 + DOS_WINDOW[0] and dos.attacker_ips == (IPS["uav1"],)
    with pytest.raises(LabelError, match="t0_unix"):
        read_attack_log(tmp_path / "absent.jsonl", plan, None)
    bad = tmp_path / "bad.jsonl"
    bad.write_text('{"event": "start", "attack_id": "x"}\nnot json\n')
    with pytest.raises(LabelError, match=r"bad.jsonl:1: record has no 'family'"):
        read_attack_log(bad)
    start = {"event": "start", "attack_id": "x", "family": "dos", "attackers": [], "attacker_ips": [],
             "victims": ["nobody"], "victim_ips": [], "t_unix": 1, "params": {}, "planned_start_s": 0.0,
             "planned_stop_s": 1.0}
    bad.write_text(json.dumps(start) + "\n")
    with pytest.raises(LabelError, match="nobody"):  # no IPs logged: the plan's, and it has no such node
        read_attack_log(bad, plan, T0)
    bad.write_text(json.dumps({**start, "colour": "red"}) + "\n")
    with pytest.raises(LabelError, match=r"bad.jsonl:1: unknown field 'colour'"):
        read_attack_log(bad, plan, T0)
    bad.write_text(json.dumps({k: v for k, v in start.items() if k != "planned_stop_s"}) + "\n")
    with pytest.raises(LabelError, match=r"bad.jsonl:1: record has no 'planned_stop_s'"):
        read_attack_log(bad, plan, T0)
    bad.write_text(json.dumps({**start, "family": "teleport"}) + "\n")
    with pytest.raises(LabelError, match=r"bad.jsonl:1: bad field value 'family'"):
        read_attack_log(bad, plan, T0)


def test_wormhole_window_and_ddos(synth_run_dir, tmp_path):
    import shutil

    run = tmp_path / "run"
    shutil.copytree(synth_run_dir, run)
    recs = [r.model_copy(update={"family": "ddos"}) if r.family == "dos" else r for r in RunDir(run).read_attacks()]
    recs += [AttackStart(attack_id="wormhole-0", family="wormhole", attackers=["uav2"], attacker_ips=[IPS["uav2"]],
                         victims=["uav0"], victim_ips=[IPS["uav0"]], t_unix=T0 + 0.5, params={},
                         planned_start_s=0.5, planned_stop_s=3.0),
             AttackStop(attack_id="wormhole-0", family="wormhole", t_unix=T0 + 3.0)]
    lines = attack_log_text(recs)
    assert lines.count('"family":"ddos"') == 3
    (run / "attacks.jsonl").write_text(lines)
    df = _labelled(run)
    worm = df[df.label_wormhole]
    assert len(worm) == 2 and (worm.src_port == 40000).all() and (worm.label == "Wormhole").all()  # session + FIN tail
    assert (worm.label_source == "victim-window").all()
    assert (df.label == "DDoS").sum() == N_FLOOD and not df.label_dos.any()
