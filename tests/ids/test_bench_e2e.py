"""End-to-end `uavcas bench ids` on a small synthetic dataset (few epochs, two seeds): the output
files, the known structure (DoS separable, Wormhole indistinguishable), degenerate splits refused,
the leaderboard."""

from __future__ import annotations

import importlib.util
import json

import numpy as np
import pandas as pd
import pytest
from sklearn.metrics import roc_auc_score
from typer.testing import CliRunner

from uavcas.cli import app
from uavcas.dataset.synthetic import write_dataset
from uavcas.ids.detectors import make_model
from uavcas.ids.features import feature_matrix
from uavcas.ids.leaderboard import COLUMNS as LEADERBOARD_COLUMNS
from uavcas.ids.results import RESULT_COLUMNS
from uavcas.ids.splits import grouped_split

runner = CliRunner()
NEEDS_TORCH = pytest.mark.skipif(importlib.util.find_spec("torch") is None,
                                 reason="PyTorch not installed (pip install '.[dl]')")


def _read(path):
    return pd.read_csv(path, keep_default_na=False, na_values=["nan", "NaN"])


def _bench(ds, out, *args):
    r = runner.invoke(app, ["bench", "ids", str(ds), "--out", str(out), "--epochs", "2", "--threads", "1",
                            "--seeds", "0,1", *args])
    assert r.exit_code == 0, r.output
    df = _read(out / "results.csv")
    assert tuple(df.columns) == RESULT_COLUMNS and set(df["seed"]) == {0, 1}
    assert (out / "results.md").is_file() and json.loads((out / "results.json").read_text())["declared"]
    return df


def _overall(df, metric):
    return df[(df["metric"] == metric) & (df["class"] == "")].groupby("model")["value"].mean()


@pytest.mark.slow  # 47 s on 2 cores
@NEEDS_TORCH
def test_multiclass_all_ten_models(synth_dir, tmp_path):
    df = _bench(synth_dir, tmp_path, "--protocol", "multiclass")
    models = sorted(df["model"].unique())
    assert len(models) == 10
    assert {"f1_macro", "f1_weighted", "accuracy", "pr_auc_macro", "fit_s"} <= set(df[df["class"] == ""]["metric"])
    per = df[~df["class"].isin(["", "stealth"])]
    assert set(per["metric"]) == {"precision", "recall", "f1", "support", "pr_auc"}
    assert per["class"].nunique() == 15
    scores = df[~df["metric"].isin(["fit_s", "epochs", "support"])]["value"].dropna()
    assert scores.between(0, 1).all()
    # macro-F1 is the mean over the 15 declared classes, whatever a model predicts
    f1 = per[per["metric"] == "f1"].groupby(["seed", "model"])["value"].mean()
    macro = df[(df["metric"] == "f1_macro") & (df["class"] == "")].set_index(["seed", "model"])["value"]
    np.testing.assert_allclose(macro.sort_index(), f1.sort_index())
    assert df[(df["metric"] == "f1_macro") & (df["class"] == "stealth")]["model"].nunique() == 10
    assert _overall(df, "f1_weighted")["RF"] > 0.6
    # confusion counts for every model: each seed's matrix sums to its test flows
    conf = _read(tmp_path / "confusion.csv")
    sizes = json.loads((tmp_path / "results.json").read_text())["sizes"]
    for (seed, _model), g in conf.groupby(["seed", "model"]):
        assert g["count"].sum() == sizes[str(seed)]["test"]
    for m in models:
        name = "".join(ch if ch.isalnum() else "_" for ch in m)
        assert (tmp_path / f"confusion_{name}.csv").is_file()
        assert (tmp_path / f"confusion_{name}.png").read_bytes()[:4] == b"\x89PNG"
    imp = _read(tmp_path / "importance.csv")
    assert set(imp["model"]) == {"RF", "LightGBM"} and imp["feature"].nunique() == 47
    splits = _read(tmp_path / "splits.csv")
    assert list(splits.columns) == ["seed", "run_id", "split"] and set(splits["split"]) == {"train", "val", "test"}
    assert splits.groupby("seed")["run_id"].nunique().tolist() == [160, 160]
    assert set(splits[splits["seed"] == 0].query("split == 'test'")["run_id"]) != set(
        splits[splits["seed"] == 1].query("split == 'test'")["run_id"])
    lb = _read(tmp_path / "leaderboard.csv")
    assert tuple(lb.columns) == LEADERBOARD_COLUMNS and (lb["std"].dropna() >= 0).all()


@pytest.mark.slow  # 10 s on 2 cores
def test_binary_dos_is_separable(synth_dir, tmp_path):
    df = _bench(synth_dir, tmp_path, "--protocol", "binary", "--models", "lr,rf", "--scaler", "robust")
    assert (_overall(df, "f1_weighted")[["LR",
                                         "RF"]] > 0.97).all() and (_overall(df, "f1_macro")[["LR", "RF"]] > 0.95).all()
    assert (_overall(df, "auroc") > 0.99).all() and (_overall(df, "pr_auc") > 0.95).all()
    assert set(_read(tmp_path / "confusion_RF.csv").columns[1:]) == {"Benign", "DoS"}


def test_all_protocols_one_leaderboard(synth_dir, tmp_path):
    r = runner.invoke(app, ["bench", "ids", str(synth_dir), "--out", str(tmp_path), "--protocol", "all",
                            "--models", "lr", "--seeds", "0,1", "--holdout", "mission=random", "--threads", "1"])
    assert r.exit_code == 0, r.output
    lb = _read(tmp_path / "leaderboard.csv")
    assert set(lb["protocol"]) == {"binary", "multiclass", "ood", "cross-condition"}
    ood = lb[(lb["protocol"] == "ood") & (lb["metric"] == "auroc") & (lb["class"] != "")].set_index("class")["mean"]
    assert len(ood) == 9 and ood["Blackhole+DoS"] > 0.95
    cc = lb[lb["protocol"] == "cross-condition"]
    assert {"f1_macro", "f1_macro_iid"} <= set(cc["metric"]) and "stealth" in set(cc["class"])
    md = (tmp_path / "leaderboard.md").read_text()
    assert "### ood" in md and "±" in md
    for p in ("binary", "multiclass", "ood", "cross-condition"):
        assert (tmp_path / p / "results.csv").is_file() and (tmp_path / p / "splits.csv").is_file()
    # the same results again through `bench leaderboard` give the same table
    r = runner.invoke(app, ["bench", "leaderboard", str(tmp_path), "--out", str(tmp_path / "lb")])
    assert r.exit_code == 0, r.output
    again = _read(tmp_path / "lb" / "leaderboard.csv")
    key = ["protocol", "model", "metric", "class"]
    pd.testing.assert_frame_equal(again.sort_values(key).reset_index(drop=True),
                                  lb.sort_values(key).reset_index(drop=True))


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


def test_quick_like_dataset_is_refused_naming_the_class(synth_df, tmp_path):
    """One run per composition (as in the quick campaign): every attack class is in one run."""
    first = synth_df.groupby("attacks")["run_id"].min()
    ds = write_dataset(tmp_path / "one-run-each", synth_df[synth_df["run_id"].isin(first)])
    for protocol, cls in (("multiclass", "Blackhole is in 1 run"), ("binary", "DoS is in 1 run")):
        r = runner.invoke(app, ["bench", "ids", str(ds), "--out", str(tmp_path / protocol), "--protocol", protocol,
                                "--models", "lr"])
        assert r.exit_code == 2 and cls in r.output and "degenerate split" in r.output, r.output
        assert not (tmp_path / protocol).exists()


@pytest.mark.slow  # 15 s on 2 cores
def test_min_class_runs_leaves_out_the_rare_classes_and_says_so(synth_df, tmp_path):
    """A class in one run makes the split degenerate; --min-class-runs 2 leaves out its flows
    instead (named, with run and flow counts, in the notes) and fits on the rest."""
    wormhole_runs = sorted(synth_df.loc[synth_df["label"] == "Wormhole", "run_id"].unique())
    keep = ~synth_df["run_id"].isin(wormhole_runs[1:])  # Wormhole left in a single run
    n_rare = int((synth_df[keep]["label"] == "Wormhole").sum())
    assert n_rare > 0
    ds = write_dataset(tmp_path / "rare", synth_df[keep])
    args = ["bench", "ids", str(ds), "--protocol", "multiclass", "--models", "lr", "--seeds", "0,1", "--no-importance"]
    r = runner.invoke(app, args + ["--out", str(tmp_path / "refused")])
    assert r.exit_code == 2 and "Wormhole is in 1 run" in r.output, r.output
    r = runner.invoke(app, args + ["--out", str(tmp_path / "kept"), "--min-class-runs", "2"])
    assert r.exit_code == 0, r.output
    res = pd.read_csv(tmp_path / "kept" / "results.csv")
    assert "Wormhole" not in set(res["class"].dropna()) and "Blackhole" in set(res["class"].dropna())
    md = (tmp_path / "kept" / "leaderboard.md").read_text()
    assert f"Wormhole (1 run, {n_rare} flows)" in md


@pytest.mark.parametrize(
    "args,msg",
    [
        (["--protocol", "nope"], "--protocol"),
        (["--models", "lr,xgb"], "--models"),
        (["--scaler", "zscore"], "--scaler"),
        (["--seeds", "0,x"], "--seeds"),
        (["--seeds", "1,1"], "--seeds"),
        (["--features", "nope", "--models", "lr"], "unknown feature set"),
        (["--protocol", "cross-condition", "--models", "lr"], "--holdout"),
        (["--protocol", "binary,cross-condition", "--models", "lr"], "--holdout"),
        (["--protocol", "cross-condition", "--models", "lr", "--holdout", "mission"], "AXIS=VALUE"),
        (["--protocol", "cross-condition", "--models", "lr", "--holdout", "run_id=run00001"], "not an axis"),
    ],
)
def test_bad_input_one_line_error(synth_dir, tmp_path, args, msg):
    r = runner.invoke(app, ["bench", "ids", str(synth_dir), "--out", str(tmp_path / "o"), *args])
    assert r.exit_code != 0
    assert msg in r.output and len(r.output.strip().splitlines()) <= 2
    assert not (tmp_path / "o").exists()


@pytest.mark.shared
def test_external_cicids_binary(shared_data, tmp_path):
    ds = shared_data / "ids-samples" / "cicids2017-improved-rnd2500"
    if not ds.is_dir():
        pytest.skip(f"{ds} not found")
    df = _bench(ds, tmp_path, "--protocol", "binary", "--models", "lr")
    assert _overall(df, "f1_weighted")["LR"] > 0.9
    notes = json.loads((tmp_path / "results.json").read_text())["notes"]
    assert any("own group" in n for n in notes)
