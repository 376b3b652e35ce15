"""Datasets say how many runs failed their fidelity audit; the report shows verdicts and figures."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

from helpers.fidsynth import Traffic, build, plan
from helpers.synth_run import build_run
from uavcas.dataset.store import extract_run
from uavcas.fidelity import audit, write_fidelity
from uavcas.rundir import FidelitySummary, RunDir


def _set_verdict(run_dir: Path, verdict: str) -> None:
    rd = RunDir(run_dir)
    info = rd.read_info().model_copy(update={"fidelity": FidelitySummary(verdict=verdict, failed=["lateness_ms"])})
    rd.run_json.write_text(info.to_json())


def test_card_counts_runs_by_fidelity_verdict(tmp_path):
    ds = tmp_path / "ds"
    runs = {"a": "pass", "b": "fail", "c": "fail", "d": None}
    for rid, verdict in runs.items():
        rd = build_run(tmp_path / rid, run_id=rid)
        if verdict:
            _set_verdict(rd, verdict)
        extract_run(rd, ds)
    card = json.loads((ds / "dataset.json").read_text())
    assert card["fidelity"] == {"pass": 1, "fail": 2, "error": 0, "unaudited": 1}
    assert {r["run_id"]: r["fidelity"] for r in card["runs"]} == runs


def test_report_shows_fidelity_verdicts_and_planned_vs_measured(tmp_path):
    from uavcas.report.fidelity import COLUMNS, fidelity_figure, fidelity_frame, read_run_fidelity

    ds = tmp_path / "ds"
    for rid, late in (("0", 0.0), ("1", 0.002)):
        tr = Traffic()
        for k in range(300):
            tr.add(0.1 + 0.005 * k, 800)
        rd = build(tmp_path / f"r{rid}", plan(loss_b=0.05), tr, error=lambda h, k, late=late: late,
                   drop=lambda h, k: h == 1 and k % 20 == 0)
        write_fidelity(rd.root)
        (ds / "runs" / rid).mkdir(parents=True)
        shutil.copy(rd.fidelity_json, ds / "runs" / rid / "fidelity.json")
    runs = read_run_fidelity(ds)
    frame = fidelity_frame(runs, {"1": "replay-..."}, {})
    assert list(frame.columns) == list(COLUMNS) and list(frame["run"]) == ["0", "1"]
    assert frame["verdict"][0] == "pass" and frame["verdict"][1].startswith("fail: delay_error_p50_ms")
    assert audit(tmp_path / "r1").verdict == "fail" and frame["config"][1] == "replay-..."
    # 15 packets dropped on hop 1: the loss rule's, none at the queue tail
    assert (frame["lost (packets)"] == 15).all() and (frame["random"] == 15).all() and (frame["queue tail"] == 0).all()
    uri = fidelity_figure(runs)
    assert uri.startswith("data:image/png;base64,") and len(uri) > 10_000
    (tmp_path / "empty" / "runs").mkdir(parents=True)
    assert read_run_fidelity(tmp_path / "empty") == {}


def test_card_counts_runs_by_mavlink_signing(tmp_path):
    ds = tmp_path / "ds"
    for rid, signed in {"a": True, "b": False, "c": False}.items():
        rd = RunDir(build_run(tmp_path / rid, run_id=rid))
        rd.run_json.write_text(rd.read_info().model_copy(update={"mavlink_signing": signed}).to_json())
        extract_run(rd.root, ds)
    card = json.loads((ds / "dataset.json").read_text())
    assert card["mavlink_signing"] == {"on": 1, "off": 2, "unknown": 0}
    assert {r["run_id"]: r["mavlink_signing"] for r in card["runs"]} == {"a": True, "b": False, "c": False}
