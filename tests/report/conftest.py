"""A quick-campaign-like dataset for the report tests: every class, what a campaign keeps per run
(plan.json of attack and benign runs, fidelity.json from real audits, one passing and one failing),
non-finite and zero feature values as CICFlowMeter writes them."""

from __future__ import annotations

import shutil
from pathlib import Path

import numpy as np
import pytest

from helpers.fidsynth import Traffic, build
from helpers.fidsynth import plan as fid_plan
from uavcas.dataset.synthetic import make_flows, write_dataset
from uavcas.fidelity import write_fidelity
from uavcas.twin.plan import plan as make_plan

PLANNED = ("run00000", "run00001", "run00007", "run00009")  # benign, dos, blackhole+dos, dos+wormhole
AUDITED = {"run00000": 0.0, "run00005": 0.002}  # run -> the emulator's lateness per hop (s): pass, fail


def _audit(root: Path, late: float):
    tr = Traffic()
    for k in range(300):
        tr.add(0.1 + 0.005 * k, 800)
    rd = build(root, fid_plan(loss_b=0.05), tr, error=lambda h, k: late, drop=lambda h, k: h == 1 and k % 20 == 0)
    return rd, write_fidelity(rd.root)


@pytest.fixture(scope="session")
def report_ds(tmp_path_factory) -> Path:
    tmp = tmp_path_factory.mktemp("report")
    df = make_flows(16, flows_per_run=8, seed=2)  # the medium preset's first 16 configurations: all 15 classes
    # a zero-duration flow as CICFlowMeter has it: no IAT (NaN), an infinite rate
    df.loc[::9, "Flow IAT Mean"] = np.nan
    df.loc[::9, "Flow Packets/s"] = np.inf
    meta, audits = {}, {}
    for rid, late in AUDITED.items():
        rd, fid = _audit(tmp / f"audit-{rid}", late)
        audits[rid] = rd.fidelity_json
        meta[rid] = {"fidelity": fid.verdict, "fidelity_failed": fid.failed}
    ds = write_dataset(tmp / "ds", df, run_meta=meta)
    for rid, src in audits.items():
        (ds / "runs" / rid).mkdir(parents=True, exist_ok=True)
        shutil.copy(src, ds / "runs" / rid / "fidelity.json")
    for rid in PLANNED:
        g = df[df["run_id"] == rid].iloc[0]
        p = make_plan(g["config"], seed=int(g["seed"]), windows=3, window_s=5.0)
        (ds / "runs" / rid).mkdir(parents=True, exist_ok=True)
        (ds / "runs" / rid / "plan.json").write_text(p.to_json())
    return ds
