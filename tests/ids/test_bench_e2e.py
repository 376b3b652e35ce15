"""End-to-end `uavcas bench ids` on a small synthetic dataset (few epochs), and the known
structure: DoS separable (F1, AUROC ~ 1), Wormhole indistinguishable (AUROC ~ 0.5)."""

from __future__ import annotations

import importlib.util
import json

import numpy as np
import pandas as pd
import pytest
from sklearn.metrics import roc_auc_score
from typer.testing import CliRunner

from uavcas.cli import app
from uavcas.ids.features import feature_matrix
from uavcas.ids.models import make_model
from uavcas.ids.splits import grouped_split

runner = CliRunner()


def _bench(ds, out, *args):
    r = runner.invoke(app, ["bench", "ids", str(ds), "--out", str(out), "--epochs", "2", "--threads", "1", *args])
    assert r.exit_code == 0, r.output
    df = pd.read_csv(out / "results.csv", keep_default_na=False)
    assert list(df.columns) == ["protocol", "model", "metric", "class", "value"]
    assert (out / "results.md").is_file() and json.loads((out / "results.json").read_text())["results"]
    return df


@pytest.mark.skipif(importlib.util.find_spec("torch") is None, reason="PyTorch not installed (pip install '.[dl]')")
def test_multiclass_all_ten_models(synth_dir, tmp_path):
    df = _bench(synth_dir, tmp_path, "--protocol", "multiclass")
    assert df["model"].nunique() == 10
    overall = df[df["class"] == ""]
    assert {"f1_macro", "f1_weighted", "accuracy"} <= set(overall["metric"])
    assert set(df[df["class"] != ""]["metric"]) == {"f1"}
    assert df["value"].astype(float).between(0, 1).all()
    rf = overall[(overall["model"] == "RF") & (overall["metric"] == "f1_weighted")]["value"].astype(float).item()
    assert rf > 0.6
    assert (tmp_path / "confusion_best_worst.png").read_bytes()[:4] == b"\x89PNG"
    assert (tmp_path / "confusion_LightGBM.csv").is_file()


def test_binary_dos_is_separable(synth_dir, tmp_path):
    df = _bench(synth_dir, tmp_path, "--protocol", "binary", "--models", "lr,rf,tinyml", "--scaler", "robust")
    w = df[(df["metric"] == "f1_weighted") & (df["class"] == "")].set_index("model")["value"].astype(float)
    m = df[(df["metric"] == "f1_macro") & (df["class"] == "")].set_index("model")["value"].astype(float)
    assert (w[["LR", "RF"]] > 0.97).all() and (m[["LR", "RF"]] > 0.95).all()


def test_ood_and_cross_condition(synth_dir, tmp_path):
    df = _bench(synth_dir, tmp_path / "ood", "--protocol", "ood", "--models", "rf")
    au = df[df["metric"] == "auroc"].set_index("class")["value"].astype(float)
    assert len(au) == 9 and au["Blackhole+DoS"] > 0.95
    df = _bench(synth_dir, tmp_path / "cc", "--protocol", "cross-condition", "--models", "lr", "--holdout", "mission=random")
    assert {"f1_macro", "f1_macro_iid"} <= set(df["metric"])


def test_indistinguishable_class_auroc_near_chance(synth_df):
    def auroc(attack: str) -> float:
        sub = synth_df[synth_df["label"].isin(["Benign", attack])]
        y = (sub["label"] == attack).to_numpy()
        sp = grouped_split(y, sub["run_id"].to_numpy(), seed=0)
        x = feature_matrix(sub)
        est = make_model("rf", random_state=0, n_threads=1).fit(x[sp.train], y[sp.train])
        return roc_auc_score(y[sp.test], est.predict_proba(x[sp.test])[:, 1])

    assert auroc("DoS") > 0.99
    assert 0.3 < auroc("Wormhole") < 0.7


@pytest.mark.parametrize(
    "args,msg",
    [
        (["--protocol", "nope"], "--protocol"),
        (["--models", "lr,xgb"], "--models"),
        (["--scaler", "zscore"], "--scaler"),
        (["--protocol", "cross-condition", "--models", "lr"], "--holdout"),
        (["--protocol", "cross-condition", "--models", "lr", "--holdout", "mission"], "AXIS=VALUE"),
        (["--protocol", "cross-condition", "--models", "lr", "--holdout", "run_id=run00001"], "not an axis"),
    ],
)
def test_bad_input_one_line_error(synth_dir, tmp_path, args, msg):
    r = runner.invoke(app, ["bench", "ids", str(synth_dir), "--out", str(tmp_path), *args])
    assert r.exit_code != 0
    assert msg in r.output and len(r.output.strip().splitlines()) <= 2
    assert not (tmp_path / "results.csv").exists()


@pytest.mark.shared
def test_external_cicids_binary(shared_data, tmp_path):
    ds = shared_data / "ids-samples" / "cicids2017-improved-rnd2500"
    if not ds.is_dir():
        pytest.skip(f"{ds} not found")
    df = _bench(ds, tmp_path, "--protocol", "binary", "--models", "lr")
    w = df[(df["metric"] == "f1_weighted") & (df["class"] == "")]["value"].astype(float).item()
    assert w > 0.9
    notes = json.loads((tmp_path / "results.json").read_text())["notes"]
    assert any("own group" in n for n in notes)
