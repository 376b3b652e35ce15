"""The context columns read the captures only: altering the attack log, the plan's attacks, the
run's identity or the label options changes labels, never a `ctx_*` value."""

from __future__ import annotations

import json
import shutil

import numpy as np
import pandas as pd
import pytest

from helpers.synth_run import IPS, make_plan
from uavcas.extract import extract
from uavcas.schema import CONTEXT_FEATURES


def _ctx(run_dir, **options) -> tuple[pd.DataFrame, pd.Series]:
    df = extract(run_dir, **options).frame.set_index("flow_id").sort_index()
    return df[list(CONTEXT_FEATURES)], df["label"]


@pytest.fixture(scope="module")
def baseline(synth_run_dir):
    return _ctx(synth_run_dir)


def _copy(synth_run_dir, tmp_path):
    return shutil.copytree(synth_run_dir, tmp_path / "run")


def _rewrite_log(run_dir, fn) -> None:
    path = run_dir / "attacks.jsonl"
    lines = [json.loads(x) for x in path.read_text().splitlines() if x.strip()]
    path.write_text("".join(json.dumps(fn(r)) + "\n" for r in lines))


def test_context_is_computed_and_varies(baseline):
    ctx, labels = baseline
    assert len(ctx) and np.isfinite(ctx.to_numpy()).all()
    assert ctx["ctx_ttl_off_frac"].max() > 0  # the replayed copies (TTL - 5)
    assert ctx["ctx_dst_unanswered_frac"].max() == 1  # the blackholed fetch
    assert labels.nunique() > 2


def test_attack_log_moved_away(synth_run_dir, tmp_path, baseline):
    run = _copy(synth_run_dir, tmp_path)
    # every attack an hour later: nothing in the capture is attributed to it any more
    _rewrite_log(run, lambda r: {**r, "t_unix": r["t_unix"] + 3600.0} if "t_unix" in r else r)
    ctx, labels = _ctx(run)
    pd.testing.assert_frame_equal(ctx, baseline[0])
    assert (labels == "Benign").all() and (baseline[1] != "Benign").any()


def test_victims_and_attackers_swapped(synth_run_dir, tmp_path, baseline):
    run = _copy(synth_run_dir, tmp_path)
    swap = {IPS["uav3"]: IPS["uav0"], IPS["uav0"]: IPS["uav3"], "uav3": "uav0", "uav0": "uav3"}
    sw = lambda v: [swap.get(x, x) for x in v] if isinstance(v, list) else swap.get(v, v)  # noqa: E731
    _rewrite_log(run, lambda r: {k: sw(v) if k in ("victims", "victim_ips", "victim_ip") else v for k, v in r.items()})
    plan = make_plan()
    plan = plan.model_copy(update={"attacks": [a.model_copy(update={"victims": [swap.get(v, v) for v in a.victims]})
                                               for a in plan.attacks]})
    (run / "plan.json").write_text(plan.to_json())
    ctx, labels = _ctx(run)
    pd.testing.assert_frame_equal(ctx, baseline[0])
    assert not labels.equals(baseline[1])


def test_run_identity_and_label_options(synth_run_dir, tmp_path, baseline):
    run = _copy(synth_run_dir, tmp_path)
    info = json.loads((run / "run.json").read_text())
    info.update(run_id="another-run", seed=12345)
    (run / "run.json").write_text(json.dumps(info))
    pd.testing.assert_frame_equal(_ctx(run)[0], baseline[0])
    pd.testing.assert_frame_equal(_ctx(run, labels="paper")[0], baseline[0])
    kept, _ = _ctx(run, min_attack_fraction=1.0)  # impure flows left out: the others keep their values
    assert len(kept) < len(baseline[0])
    pd.testing.assert_frame_equal(kept, baseline[0].loc[kept.index])


def test_without_context(synth_run_dir):
    frame = extract(synth_run_dir, context=False).frame
    assert not any(c.startswith("ctx_") for c in frame.columns)
