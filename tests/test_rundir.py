"""RunDir and RunInfo: one list of run files, strict run.json, plans from before typed scenarios."""

from __future__ import annotations

import json
import shutil

import pytest

from helpers.synth_run import CONFIG, build_run, run_info
from uavcas.extract import extract
from uavcas.rundir import RunDir, RunDirError, RunInfo
from uavcas.twin.load import plan_from_data, read_plan
from uavcas.twin.plan import plan


@pytest.fixture(scope="module")
def run_dir(tmp_path_factory):
    return build_run(tmp_path_factory.mktemp("rd") / "run-synth")


def test_paths_and_the_one_list_of_run_files(tmp_path):
    rd = RunDir(tmp_path)
    assert [p.name for p in rd.files()] == ["plan.json", "run.json", "attacks.jsonl", "shaping.jsonl",
                                          "forwarding.jsonl", "fidelity.json"]
    assert (rd.pcap_dir, rd.logs_dir) == (tmp_path / "pcap", tmp_path / "logs")
    assert rd.read_owner() is None and rd.read_info() is None and rd.read_attacks() == []
    rd.owner_path.write_text('{"prefix": "uc0001", "pid": 7, "started_unix": 1.5}')
    assert rd.read_owner().prefix == "uc0001"
    rd.owner_path.write_text('{"prefix": "uc0001"}')
    with pytest.raises(RunDirError, match="not a uavcas run marker"):
        rd.read_owner()
    with pytest.raises(RunDirError, match="no plan.json"):
        rd.read_plan()


def test_run_info_is_strict(run_dir, tmp_path):
    rd = RunDir(tmp_path / "r")
    shutil.copytree(run_dir, rd.root)
    info = rd.read_info()
    assert isinstance(info, RunInfo) and info.run_id == "run-synth" and info == run_info(**info.model_dump())
    d = json.loads(rd.run_json.read_text())
    for bad, msg in [({**d, "colour": 1}, "unknown field 'colour'"),
                     ({k: v for k, v in d.items() if k != "exit_status"}, "has no field 'exit_status'"),
                     ({**d, "timings": {"setup_s": 1.0, "lunch_s": 3}}, "unknown field 'timings.lunch_s'")]:
        rd.run_json.write_text(json.dumps(bad))
        with pytest.raises(RunDirError, match=msg):
            rd.read_info()
    rd.run_json.write_text("{")
    with pytest.raises(RunDirError, match="not JSON"):
        rd.read_info()


def test_plans_carry_the_typed_scenario_and_older_plan_json_still_loads():
    p = plan("blackhole+dos=1000-5-2-image-logdist-adaptive-grid-30-95", seed=3, windows=2)
    assert p.scenario.families == ("blackhole", "dos") and p.attacks[1].spec == p.scenario.attacks[1]
    old = json.loads(p.to_json())
    del old["scenario"]
    for a in old["attacks"]:
        del a["spec"]
    assert read_plan(json.dumps(old)) == p  # filled from config and params, by the families
    hand = plan_from_data({**old, "config": "test"})
    assert hand.scenario is None and hand.attacks[1].spec.interval_us == 1000


def test_extract_takes_the_axes_from_the_plans_scenario(run_dir, tmp_path):
    shard = extract(run_dir, run_id="17")
    assert shard.info.run_id == "17" and (shard.frame["run_id"] == "17").all()
    assert (shard.frame["attacks"] == "blackhole+dos=1000+replay=50,200,10,5,inc").all()
    assert (shard.frame["config"] == CONFIG).all() and shard.info.n_flows == len(shard.frame)
    rd = RunDir(tmp_path / "r")
    shutil.copytree(run_dir, rd.root)
    p = rd.read_plan()
    rd.plan_json.write_text(p.model_copy(update={"config": "test", "scenario": None}).to_json())
    with pytest.raises(RunDirError, match="no scenario"):
        extract(rd.root)


def test_forwarding_log_reads_back_and_names_a_bad_line(tmp_path):
    from uavcas.rundir import ForwardingEpoch

    rd = RunDir(tmp_path)
    assert rd.read_forwarding() == []
    ep = ForwardingEpoch(t_begin_unix=1.0, t_unix=1.5, window=0, next_hop={"uav0": {"bs0": "uav1"}})
    rd.forwarding_jsonl.write_text(ep.model_dump_json() + "\n\n" + '{"t_unix": 2.0}\n')
    with pytest.raises(RunDirError, match="forwarding.jsonl:3"):
        rd.read_forwarding()
    rd.forwarding_jsonl.write_text(ep.model_dump_json() + "\n")
    assert rd.read_forwarding() == [ep]
