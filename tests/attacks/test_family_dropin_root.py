"""A dropped-in attack family run on real stacks (root): see test_family_dropin.py for the family
(`helpers.family_dropin`: `synflood`, one vocabulary row and one module)."""

from __future__ import annotations

import json

import pyarrow.parquet as pq

from helpers.family_dropin import copy_with_throwaway
from helpers.plugin import run_on


def test_the_dropped_in_family_runs_on_real_stacks(tmp_path):
    """The same copy, run for real (hping3 paced by the flood's tool from the family's executor):
    its extracted flows carry its class."""
    pkg = copy_with_throwaway(tmp_path)
    run_dir, ds = tmp_path / "run", tmp_path / "ds"
    ran = run_on(pkg, "-m", "uavcas", "run", "synflood=1000-3-1-image-logdist-adaptive-grid-30-95", "--windows", "4",
               "--window-s", "3", "--out", str(run_dir))
    assert ran.returncode == 0, ran.stderr[-2000:]
    log = [json.loads(line) for line in (run_dir / "attacks.jsonl").read_text().splitlines()]
    assert {r["family"] for r in log if r["event"] == "start"} == {"synflood"}
    made = run_on(pkg, "-m", "uavcas", "extract", str(run_dir), "--out", str(ds))
    assert made.returncode == 0, made.stderr[-2000:]
    flows = pq.read_table(ds / "flows.parquet").to_pandas()
    assert (flows["label"] == "SYNFlood").sum() > 0
    assert set(flows.loc[flows["label_synflood"], "label_source"]) == {"synflood-packets"}
