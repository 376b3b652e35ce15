"""`uavcas extract` refuses runs that did not finish cleanly, unless told, and then marks them."""

from __future__ import annotations

import json
import shutil

import pytest
from typer.testing import CliRunner

from uavcas.cli import app
from uavcas.extract import extract
from uavcas.rundir import RunDir, RunDirError

runner = CliRunner()


def _copy(src, dst, exit_status: int | None, reason: str = "interrupted (SIGINT)"):
    shutil.copytree(src, dst)
    rd = RunDir(dst)
    if exit_status is None:  # SIGKILLed: the run never wrote run.json
        rd.run_json.unlink()
    else:
        info = json.loads(rd.run_json.read_text())
        info.update(exit_status=exit_status, exit_reason=reason)
        rd.run_json.write_text(json.dumps(info))
    return dst


@pytest.mark.parametrize("status, says", [(None, "no run.json"), (1, "exit status 1"), (130, "exit status 130"),
                                          (143, "exit status 143")])
def test_extract_refuses_a_killed_or_failed_run(synth_run_dir, tmp_path, status, says):
    run = _copy(synth_run_dir, tmp_path / "run", status)
    with pytest.raises(RunDirError, match=says):
        extract(run)
    r = runner.invoke(app, ["extract", str(run), "--out", str(tmp_path / "ds")])
    assert r.exit_code == 2 and says in r.output and "--allow-incomplete" in r.output
    assert not (tmp_path / "ds").exists()


def test_allow_incomplete_marks_the_shard_and_the_card(synth_run_dir, tmp_path):
    ds = tmp_path / "ds"
    assert runner.invoke(app, ["extract", str(synth_run_dir), "--out", str(ds)]).exit_code == 0
    killed = _copy(synth_run_dir, tmp_path / "killed", None)
    r = runner.invoke(app, ["extract", str(killed), "--out", str(ds), "--allow-incomplete"])
    assert r.exit_code == 0, r.output
    assert "incomplete" in r.output
    card = json.loads((ds / "dataset.json").read_text())
    marks = {run["run_id"]: (run["complete"], run["run_exit_status"]) for run in card["runs"]}
    assert marks == {"run-synth": (True, 0), "killed": (False, None)} and card["n_incomplete_runs"] == 1
