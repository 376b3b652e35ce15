"""Labels from per-packet effects on the synthetic run: floods, replays, blackhole drops, wormhole
detours, channel losses; the purity threshold, the views and the paper option."""

from __future__ import annotations

import json
import shutil

import pytest

from helpers.synth_run import BLACKHOLE_WINDOW, DOS_WINDOW, IPS, N_FLOOD, T0, add_wormhole, make_plan
from uavcas.events import attack_log_text
from uavcas.extract import extract
from uavcas.labels import LabelError, read_attack_log
from uavcas.rundir import RunDir
from uavcas.schema import LABEL_COLUMNS, TRUTH_COLUMNS


def _labelled(run_dir, mode="ours", view="5tuple", min_attack_fraction=0.0):
    return extract(run_dir, view=view, labels=mode, min_attack_fraction=min_attack_fraction).frame


def _effects(df):
    return [list(x) for x in df["seq_effect"]]


def test_flood_flows_are_dos_only_inside_window(synth_run_dir):
    df = _labelled(synth_run_dir)
    pair = df[(df.src_ip == IPS["uav1"]) & (df.dst_ip == IPS["uav0"])]
    inside = pair[(pair.first_ts >= T0 + DOS_WINDOW[0]) & (pair.first_ts < T0 + DOS_WINDOW[1])]
    outside = pair.drop(inside.index)
    assert len(inside) == N_FLOOD and (inside.label == "DoS").all() and inside.label_dos.all()
    assert (inside.label_source == "flood-packets").all()
    # the SYN is the flood; the victim's SYN-ACK and the attacker's RST answering it are provoked
    # by it, counted for the DoS
    assert sorted(inside.packets.unique()) == [1, 3]
    assert (inside.attack_packets == inside.packets).all() and (inside.attack_packets_dos == inside.packets).all()
    assert (inside.provoked_packets == inside.packets - 1).all()
    assert all(e == ["flood"] + ["provoked"] * (len(e) - 1) for e in _effects(inside))
    # two sessions outside, one flow each (one connection, one flow: flows.termination)
    assert outside.src_port.nunique() == 2 and len(outside) == 2
    assert (outside.label == "Benign").all() and (outside.label_source == "none").all()
    assert not df[(df.src_ip == IPS["bs0"])].label_dos.any()


def test_a_flood_stop_with_syns_still_crossing_keeps_them_flood(synth_run_dir, tmp_path):
    """A flood's stop is when its gates closed; `crossed_unix` is when its last SYN can have crossed
    the network (issue 28, item 5). SYNs captured in between left before the stop: still flood."""
    run = tmp_path / "run"
    shutil.copytree(synth_run_dir, run)
    log = run / "attacks.jsonl"
    records = [json.loads(x) for x in log.read_text().splitlines()]
    t_closed = T0 + DOS_WINDOW[0] + 0.1 + 0.19 * (N_FLOOD // 2) - 0.05  # half the SYNs captured after it

    def with_stop(crossed):
        for r in records:
            if r["event"] == "stop" and r["attack_id"] == "dos-0":
                r["t_unix"], r["crossed_unix"] = t_closed, crossed
        log.write_text("".join(json.dumps(r) + "\n" for r in records))
        df = _labelled(run)
        return df[(df.src_ip == IPS["uav1"]) & (df.dst_ip == IPS["uav0"]) & (df.label == "DoS")]

    assert len(with_stop(T0 + DOS_WINDOW[1])) == N_FLOOD
    assert len(with_stop(None)) == N_FLOOD // 2  # without it, the crossing half would be Benign
    window = read_attack_log(log).of_family("dos")[0]
    assert window.stop_unix == t_closed and window.observed_until_unix == t_closed


def test_replay_blackhole_and_channel_loss(synth_run_dir):
    df = _labelled(synth_run_dir)
    (rep,) = df[df.label_replay].itertuples()
    assert rep.src_port == 41001 and rep.label_source == "replay-injections"
    # the session (12 packets) plus the three injected copies, 1.3 s after its close (within the
    # close grace period: they join the connection they copy)
    assert rep.packets == 12 + 3 and rep.attack_packets == rep.attack_packets_replay == 3  # the injected copies only
    assert rep.attack_fraction == 3 / 15 and list(rep.seq_effect).count("replay") == 3
    bh = df[df.label_blackhole]
    assert len(bh) == 1 and bh.iloc[0].dst_ip == IPS["uav3"] and bh.iloc[0].label == "Blackhole"
    assert bh.iloc[0].label_source == "blackhole-drops" and list(bh.iloc[0].seq_effect) == ["blackhole"] * 3
    assert T0 + BLACKHOLE_WINDOW[0] <= bh.iloc[0].first_ts < T0 + BLACKHOLE_WINDOW[1]
    # the victim's flows outside the window, with nothing affected, are Benign
    victim = df[(df.dst_ip == IPS["uav3"]) & ~df.label_blackhole & ~df.label_replay]
    assert len(victim) == 4 and (victim.label == "Benign").all() and (victim.attack_packets == 0).all()
    (lossy,) = df[(df.src_port == 41002) & (df.packets == 12)].itertuples()
    assert list(lossy.seq_effect).count("channel_loss") == 1 and lossy.label == "Benign" and lossy.attack_packets == 0
    counts = df.label.value_counts().to_dict()
    assert counts == {"DoS": N_FLOOD, "Benign": 12, "Replay": 1, "Blackhole": 1}
    assert set(LABEL_COLUMNS) | set(TRUTH_COLUMNS) <= set(df.columns)
    assert (df.attack_fraction == df.attack_packets / df.packets).all()
    assert (df.attack_packets == df[[c for c in TRUTH_COLUMNS if c.startswith("attack_packets_")]].sum(axis=1)).all()
    assert (df.seq_effect.map(len) == df.packets).all()


def test_min_attack_fraction_leaves_out_impure_flows(synth_run_dir):
    shard = extract(synth_run_dir, min_attack_fraction=0.7)
    df = shard.frame
    assert not df.label_replay.any()  # 3 of 5 packets injected
    assert (df.label == "DoS").sum() == N_FLOOD  # SYN + the SYN-ACK and RST it provoked: all attack packets
    assert shard.info.impure_dropped == 1 and shard.info.min_attack_fraction == 0.7
    assert ((df.attack_packets == 0) | (df.attack_fraction >= 0.7)).all()
    assert "attack_fraction < 0.7" in shard.info.label_rule
    assert shard.info.effect_counts["replay"] == 3 and shard.info.effect_counts["channel_loss"] == 1
    # each answered flood SYN: its SYN-ACK and the RST, each seen at the switches of uav0 (and bs0: no)
    assert shard.info.effect_counts["provoked"] == 2 * (N_FLOOD // 5)
    with pytest.raises(ValueError, match="min_attack_fraction"):
        extract(synth_run_dir, min_attack_fraction=1.5)


def test_paper_ip_membership(synth_run_dir):
    df = _labelled(synth_run_dir, mode="paper")
    assert (df.label_source == "ip-membership").all()
    # no time gating: the benign uav1 -> uav0 sessions outside the window are DoS too
    pair = df[(df.src_ip == IPS["uav1"])]
    assert (pair.label == "DoS").all() and len(pair) == N_FLOOD + 2
    assert (df[df.dst_ip == IPS["uav3"]].label == "Blackhole+Replay").all()
    assert df.attack_packets.sum() == _labelled(synth_run_dir).attack_packets.sum()  # effects do not depend on it


def test_hostpair_views_labels(synth_run_dir):
    df = _labelled(synth_run_dir, view="hostpair")
    flood = df[(df.src_ip == IPS["uav1"]) | (df.dst_ip == IPS["uav1"])]
    assert len(flood) == 1 and flood.iloc[0].label == "DoS"
    win = _labelled(synth_run_dir, view="window-hostpair", min_attack_fraction=0.0)
    # one flow per host pair per 5 s window (with >= 10 packets): bs0-uav0 in the 6 windows it talks in
    bu = win[((win.src_ip == IPS["bs0"]) & (win.dst_ip == IPS["uav0"]))
             | ((win.src_ip == IPS["uav0"]) & (win.dst_ip == IPS["bs0"]))]
    assert len(bu) == 6 and len(set(((bu.first_ts - T0) // 5).astype(int))) == 6
    assert (win.last_ts - win.first_ts < 5.0).all() and (win.src_port == 0).all()
    fl = win[win.label_dos]
    # the flood spans windows 4 and 5; every 5th SYN provoked a SYN-ACK and an RST
    assert len(fl) == 2 and fl.attack_packets.sum() == N_FLOOD + 2 * (N_FLOOD // 5)
    assert fl.provoked_packets.sum() == 2 * (N_FLOOD // 5)


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


def test_wormhole_detour_and_ddos(synth_run_dir, tmp_path):
    run = tmp_path / "run"
    shutil.copytree(synth_run_dir, run)
    recs = [r.model_copy(update={"family": "ddos"}) if r.family == "dos" else r for r in RunDir(run).read_attacks()]
    lines = attack_log_text(recs)
    assert lines.count('"family":"ddos"') == 3
    (run / "attacks.jsonl").write_text(lines)
    add_wormhole(run)
    df = _labelled(run)
    worm = df[df.label_wormhole]
    # the detoured session, one flow, every packet detoured
    assert len(worm) == 1 and (worm.src_port == 40000).all() and (worm.label == "Wormhole").all()
    assert (worm.label_source == "wormhole-detour").all() and (worm.attack_fraction == 1.0).all()
    # the victim's other flows during the attack did not cross the attacker's switch: Benign
    assert not df[(df.dst_ip == IPS["uav0"]) & (df.src_port != 40000)].label_wormhole.any()
    assert (df.label == "DDoS").sum() == N_FLOOD and not df.label_dos.any()
    # a plan without the detour in that window: the same packets are no wormhole
    (run / "plan.json").write_text(make_plan().to_json())
    assert not _labelled(run).label_wormhole.any()


def test_cli_extract_records_the_rule_in_the_card(synth_run_dir, tmp_path):
    from typer.testing import CliRunner

    from uavcas.cli import app
    from uavcas.flows import FlowConfig

    out = tmp_path / "ds"
    r = CliRunner().invoke(app, ["extract", str(synth_run_dir), "--out", str(out), "--min-attack-fraction", "0.7"])
    assert r.exit_code == 0, r.output
    assert "1 flow(s) left out" in r.output
    card = json.loads((out / "dataset.json").read_text())
    (rule,) = card["label_rules"]
    assert "attack_fraction < 0.7" in rule and "blackhole:" in rule and "wormhole:" in rule
    assert card["effect_counts"]["replay"] == 3 and card["runs"][0]["impure_dropped"] == 1
    assert "provoked: the victim's SYN-ACKs" in rule and card["effect_counts"]["provoked"] == 2 * (N_FLOOD // 5)
    bad = CliRunner().invoke(app, ["extract", str(synth_run_dir), "--out", str(tmp_path / "no"),
                                   "--min-attack-fraction", "1.5"])
    assert bad.exit_code == 2 and not (tmp_path / "no").exists()
    with pytest.raises(ValueError, match="window-hostpair"):
        FlowConfig(view="window-hostpair")  # it needs the run's t0 and window length
