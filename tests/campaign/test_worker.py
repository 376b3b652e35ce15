"""The campaign's worker (typed result from a child interpreter) and its one retry rule."""

from __future__ import annotations

from dataclasses import dataclass

import pytest

from helpers.fakerun import realize_stub
from uavcas.campaign import worker
from uavcas.campaign.retry import Retries
from uavcas.campaign.worker import WorkerRequest, WorkerResult, realize_in_child
from uavcas.rundir import RunDir


@dataclass
class _Out:
    index: int
    ok: bool


def test_retries_a_failure_n_times_then_gives_up():
    seen = []
    r = Retries(2, on_retry=lambda out, attempt: seen.append((out.index, attempt)))
    assert r.started(7) == 1 and r.again(_Out(7, False))
    assert r.started(7) == 2 and r.again(_Out(7, False))
    assert r.started(7) == 3 and not r.again(_Out(7, False))
    assert seen == [(7, 1), (7, 2)]
    assert r.started(8) == 1 and not r.again(_Out(8, True))


def _req(tmp_path, config: str):
    return WorkerRequest(config=config, seed=0, windows=1, window_s=1.0, out_dir=str(tmp_path / "r"))


def test_a_failure_in_the_child_comes_back_as_a_typed_one_line_result(tmp_path):
    res = realize_in_child(_req(tmp_path, "benign-3-1-image-logdist-adaptive-ellipse-30-95"), limit_s=120)
    assert isinstance(res, WorkerResult) and not res.ok and res.exit_status == 1
    assert res.error.startswith("ScenarioError: field 'mission'") and "\n" not in res.error
    assert not (tmp_path / "r").exists()  # nothing created


def test_a_child_over_its_limit_is_stopped(tmp_path):
    # an invalid scenario, so even a child that got further than its start-up would create nothing
    res = realize_in_child(_req(tmp_path, "benign-3-1-image-logdist-adaptive-ellipse-30-95"), limit_s=0.01)
    assert not res.ok and res.exit_status == 124 and "did not finish" in res.error


@pytest.mark.parametrize("exit_status", [0, 1])
def test_the_worker_audits_a_run_that_finished_and_only_that(tmp_path, monkeypatch, exit_status):
    """The runner does not audit: the worker does after it, and the campaign's fidelity policy
    reads the verdict it leaves in run.json."""
    monkeypatch.setattr(worker, "preflight", lambda p, out: None)
    monkeypatch.setattr(worker, "probe_kernel", lambda: (None, None))
    monkeypatch.setattr(worker, "realize", realize_stub(exit_status))
    res = worker.realize_request(_req(tmp_path, "benign-3-1-image-logdist-adaptive-random-30-95"))
    rd = RunDir(tmp_path / "r")
    assert res.ok == (exit_status == 0) and res.exit_status == exit_status
    if exit_status == 0:
        assert rd.fidelity_json.exists() and rd.read_info().fidelity.verdict == "pass"
    else:
        assert not rd.fidelity_json.exists() and rd.read_info().fidelity is None
