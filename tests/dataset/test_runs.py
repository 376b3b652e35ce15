"""The runs of a dataset with their verdicts and failed checks: `uavcas info`, the campaign summary."""

from __future__ import annotations

import re
import shutil

import pytest
from typer.testing import CliRunner

from helpers.fidsynth import Traffic, build, plan
from uavcas.cli import app
from uavcas.dataset.runs import dataset_runs, flagged_lines, percent
from uavcas.dataset.store import read_card
from uavcas.dataset.synthetic import make_flows, write_dataset
from uavcas.fidelity import write_fidelity


@pytest.fixture(scope="module")
def flagged_ds(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("runs")
    tr = Traffic()
    for k in range(200):
        tr.add(0.1 + 0.005 * k, 800)
    rd = build(tmp / "late", plan(), tr, error=lambda h, k: 0.002)  # 2 ms late per hop: fails the delay checks
    fid = write_fidelity(rd.root)
    meta = {"run00001": {"fidelity": fid.verdict, "fidelity_failed": fid.failed},
            "run00002": {"fidelity": "error", "fidelity_failed": ["audit error: no captures"]},
            "run00003": {"fidelity": "pass"}}
    ds = write_dataset(tmp / "ds", make_flows(4, flows_per_run=6, seed=1), run_meta=meta)
    (ds / "runs" / "run00001").mkdir(parents=True)
    shutil.copy(rd.fidelity_json, ds / "runs" / "run00001" / "fidelity.json")
    return ds


def test_runs_carry_verdict_and_failed_checks_with_value_and_limit(flagged_ds):
    runs = dataset_runs(flagged_ds, read_card(flagged_ds))
    assert [r.run_id for r in runs] == ["run00000", "run00001", "run00002", "run00003"]
    assert [r.verdict for r in runs] == ["unaudited", "fail", "error", "pass"]
    assert [r.flagged for r in runs] == [False, True, True, False]
    assert runs[1].failed[0] == "delay_error_p50_ms 2 (limit <= 0.1)" and runs[1].rows == 6
    assert sum(runs[1].classes.values()) == 6
    lines = flagged_lines(runs)
    assert len(lines) == 2 and lines[0].startswith("run run00001 (dos=1000-5-2-mixed")
    assert "delay_error_p99_ms 2" in lines[0]
    assert lines[1].endswith("error: audit error: no captures")


def test_percent_never_prints_zero_for_a_count():
    assert percent(13, 27851) == "<0.1%" and percent(0, 27851) == "0.0%" and percent(27850, 27851) == ">99.9%"
    assert percent(1, 4) == "25.0%" and percent(4, 4) == "100.0%" and percent(0, 0) == "-"


def test_info_shows_runs_fidelity_and_flagged(flagged_ds):
    r = CliRunner().invoke(app, ["info", str(flagged_ds)], env={"COLUMNS": "300"})
    assert r.exit_code == 0, r.output
    out = r.output
    assert "fidelity: 1 pass, 1 fail, 1 error, 1 unaudited; 2 run(s) kept flagged" in out
    assert "fail: delay_error_p50_ms 2 (limit <= 0.1)" in out and "error: audit error: no captures" in out
    assert "dos=1000-5-2-mixed-logdist-adaptive-spiral-30-95" in out
    assert "0.0%" in out and not re.search(r"[1-9]\d*\s+│\s+0\.0%", out)  # 0.0% only for a class with no flow
