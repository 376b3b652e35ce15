"""`uavcas run` audits the run it realised (stage 2b), unless `--no-audit`: the runner does not."""

from __future__ import annotations

from types import SimpleNamespace

import pytest
from typer.testing import CliRunner

from helpers.fakerun import realize_stub
from uavcas.cli import app
from uavcas.cli import run as run_cli
from uavcas.fidelity import read_fidelity
from uavcas.rundir import RunDir

CONFIG = "benign-3-1-image-logdist-adaptive-random-30-95"


@pytest.fixture
def stub_runner(monkeypatch):
    """No root: preflight passes, the kernel probe names a backend, the run is fidsynth's."""
    monkeypatch.setattr(run_cli, "preflight", lambda p, out: None)
    monkeypatch.setattr(run_cli, "probe_kernel", lambda: (SimpleNamespace(shaper="stub"), None))

    def use(exit_status: int) -> None:
        monkeypatch.setattr(run_cli, "realize", realize_stub(exit_status))
    return use


def _run(out, *more: str):
    return CliRunner().invoke(app, ["run", CONFIG, "--windows", "1", "--window-s", "1", "--out", str(out), *more])


def test_run_audits_the_finished_run(tmp_path, stub_runner):
    stub_runner(0)
    r = _run(tmp_path / "r")
    assert r.exit_code == 0, r.output
    f, info = read_fidelity(tmp_path / "r"), RunDir(tmp_path / "r").read_info()
    assert f is not None and f.verdict == "pass" and info.fidelity.verdict == "pass"
    assert "fidelity" in r.output.lower()  # the summary line, from the audited run.json


def test_no_audit_and_a_failed_run_leave_no_audit(tmp_path, stub_runner):
    stub_runner(0)
    assert _run(tmp_path / "a", "--no-audit").exit_code == 0
    stub_runner(1)
    assert _run(tmp_path / "b").exit_code == 1
    for out in (tmp_path / "a", tmp_path / "b"):
        assert read_fidelity(out) is None and RunDir(out).read_info().fidelity is None
