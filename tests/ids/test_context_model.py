"""The context detector and its ablation: inputs selected by column name, and `bench ids
--models context,context-flow,context-only` end to end on a dataset with context columns."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest
from typer.testing import CliRunner

from uavcas.cli import app
from uavcas.dataset.synthetic import write_dataset
from uavcas.flows.standards.cic import FEATURES
from uavcas.ids import baseline, detectors
from uavcas.ids.context import class_weights, select_columns
from uavcas.schema import CONTEXT_FEATURES

runner = CliRunner()


def _frame(n=400, seed=0):
    """A flow feature and a context column; the class follows the context column only."""
    rng = np.random.default_rng(seed)
    ctx = rng.normal(size=n)
    X = pd.DataFrame({"Flow Duration": rng.normal(size=n), "ctx_ttl_off_frac": ctx})
    return X, np.where(ctx > 0, "Replay", "Benign")


@pytest.mark.parametrize("name,learns", [("context", True), ("context-joint", True), ("context-only", True),
                                         ("context-flow", False)])
def test_each_variant_sees_only_its_inputs(name, learns):
    X, y = _frame()
    Xt, yt = _frame(seed=1)
    est = baseline(name, n_jobs=1).fit(X, y)
    acc = (est.predict(Xt) == yt).mean()
    assert (acc > 0.95) if learns else (acc < 0.7)
    assert list(est.feature_names_in_) == {"context": list(X.columns), "context-joint": list(X.columns),
                                           "context-only": ["ctx_ttl_off_frac"],
                                           "context-flow": ["Flow Duration"]}[name]


def test_context_stage_adds_to_the_flow_models_scores():
    """Two stages with named columns: the probabilities are the softmax of the flow model's raw
    scores plus the context trees'; without names (an array) one model learns everything."""
    rng = np.random.default_rng(0)
    n = 600
    X = pd.DataFrame({"Flow Duration": rng.normal(size=n), "ctx_ttl_off_frac": rng.normal(size=n)})
    y = np.select([X["Flow Duration"] > 0.5, X["ctx_ttl_off_frac"] > 0.5], ["DoS", "Replay"], "Benign")
    est = baseline("context", n_jobs=1).fit(X, y)
    z = (est.flow_model_.predict(X[["Flow Duration"]].to_numpy(), raw_score=True)
         + np.clip(est.model_.predict(X.to_numpy(), raw_score=True), -est.context_bound, est.context_bound))
    np.testing.assert_allclose(est.predict_proba(X), np.exp(z) / np.exp(z).sum(1, keepdims=True), rtol=1e-9)
    # the flow stage alone cannot tell Replay from Benign; the context stage can
    Xt = pd.DataFrame({"Flow Duration": rng.normal(size=n), "ctx_ttl_off_frac": rng.normal(size=n)})
    yt = np.select([Xt["Flow Duration"] > 0.5, Xt["ctx_ttl_off_frac"] > 0.5], ["DoS", "Replay"], "Benign")
    flow_only = est.classes_[est.flow_model_.predict(Xt[["Flow Duration"]].to_numpy(), raw_score=True).argmax(1)]
    rest = yt != "DoS"
    assert (flow_only[rest] == yt[rest]).mean() < 0.75 and (est.predict(Xt)[rest] == yt[rest]).mean() > 0.9
    assert baseline("context", n_jobs=1).fit(X.to_numpy(), y).flow_model_ is None
    assert baseline("context-joint", n_jobs=1).fit(X, y).flow_model_ is None


def test_the_context_stage_cannot_overturn_a_confident_flow_decision():
    """Bounded at b, the context moves a raw score by at most b: a flow decision held at more than
    b log-odds stands, however far the context columns lie from the training runs'."""
    rng = np.random.default_rng(0)
    n = 800
    X = pd.DataFrame({"Flow Duration": rng.normal(size=n), "ctx_ttl_off_frac": rng.normal(size=n)})
    # the context column flips the label where it is high: the context stage learns a large correction
    y = np.where((X["Flow Duration"] > 0) ^ (X["ctx_ttl_off_frac"] > 1.5), "DoS", "Benign")
    Xt = X.assign(ctx_ttl_off_frac=rng.uniform(3, 6, size=n))  # context out of the training range
    free = baseline("context", n_jobs=1, context_bound=None).fit(X, y)
    bounded = baseline("context", n_jobs=1, context_bound=0.5).fit(X, y)
    flow = bounded.flow_model_.predict(Xt[["Flow Duration"]].to_numpy(), raw_score=True)
    correction = free.model_.predict(Xt.to_numpy(), raw_score=True)
    sure = np.abs(flow) > 0.5
    assert sure.sum() > 100 and np.abs(correction[sure]).max() > 0.5  # unbounded, it could flip them
    flow_call = np.where(flow > 0, "DoS", "Benign")
    assert (bounded.predict(Xt)[sure] == flow_call[sure]).all()
    assert (free.predict(Xt)[sure] != flow_call[sure]).any()


def test_selection_by_name_and_refusals():
    cols = ["Flow Duration", "ctx_rtt_ms", "ctx_lost_frac"]
    assert select_columns(cols, "both") == cols
    assert select_columns(cols, "flow") == ["Flow Duration"]
    assert select_columns(cols, "context") == ["ctx_rtt_ms", "ctx_lost_frac"]
    assert select_columns(None, "context") is None  # an array: taken whole
    with pytest.raises(ValueError, match="no such column"):
        select_columns(["Flow Duration"], "context")
    with pytest.raises(ValueError, match="inputs"):
        select_columns(cols, "everything")
    X, y = _frame()
    est = baseline("context-only", n_jobs=1).fit(X, y)
    with pytest.raises(ValueError, match="lacks the columns"):
        est.predict(X[["Flow Duration"]])
    # without names every column is used
    assert baseline("context-flow", n_jobs=1).fit(X.to_numpy(), y).n_features_in_ == 2


@pytest.mark.slow  # 167 s on 2 cores
def test_bench_context_models_with_importance(synth_dir, tmp_path):
    context = ",".join(s.name for s in detectors() if s.uses_context)
    r = runner.invoke(app, ["bench", "ids", str(synth_dir), "--out", str(tmp_path), "--protocol", "multiclass",
                            "--models", context, "--seeds", "0", "--threads", "1"])
    assert r.exit_code == 0, r.output
    res = pd.read_csv(tmp_path / "results.csv", keep_default_na=False)
    assert set(res["model"]) == {"Context", "Context-joint", "Context-flow", "Context-only"}
    assert "stealth" in set(res["class"])
    imp = pd.read_csv(tmp_path / "importance.csv")
    feats = imp.groupby("model")["feature"].agg(set)
    # every context model is given the flow features and the context columns; each uses its own
    assert all(f == set(FEATURES) | set(CONTEXT_FEATURES) for f in feats)
    flow_only = imp[imp["model"] == "Context-flow"]
    assert (flow_only[flow_only["feature"].str.startswith("ctx_")]["mean"] == 0).all()
    ctx_only = imp[imp["model"] == "Context-only"]
    assert (ctx_only[~ctx_only["feature"].str.startswith("ctx_")]["mean"] == 0).all()
    lb = (tmp_path / "leaderboard.md").read_text()
    assert "Context-only" in lb


@pytest.mark.slow  # 11 s on 2 cores
def test_bench_context_needs_context_columns(synth_df, tmp_path):
    ds = write_dataset(tmp_path / "no-ctx", synth_df.drop(columns=list(CONTEXT_FEATURES)))
    r = runner.invoke(app, ["bench", "ids", str(ds), "--out", str(tmp_path / "o"), "--models", "lr,context"])
    assert r.exit_code == 2 and "no context columns" in r.output and len(r.output.strip().splitlines()) <= 3, r.output
    assert not (tmp_path / "o").exists()
    # the baselines alone do not need them
    r = runner.invoke(app, ["bench", "ids", str(ds), "--out", str(tmp_path / "lr"), "--models", "lr",
                            "--seeds", "0", "--no-importance"])
    assert r.exit_code == 0, r.output


def test_context_detector_on_episode_rows():
    """The window-host view's context columns are the episode summaries (`context_columns`), more
    than the flows' ctx_*: the context models must be given their names (a mismatch raised)."""
    from uavcas.ids.features import context_columns, feature_sets
    from uavcas.ids.protocols import BenchConfig, run_protocol
    from uavcas.schema import EPISODE_CONTEXT_FEATURES, EPISODE_VIEW

    rng = np.random.default_rng(0)
    n = 12 * 40
    df = pd.DataFrame({c: rng.normal(size=n) for c in feature_sets()[f"{EPISODE_VIEW}-cic"]})
    ctx = pd.DataFrame({c: rng.normal(size=n) for c in EPISODE_CONTEXT_FEATURES})
    df = pd.concat([df, ctx], axis=1)
    df["label"] = np.where(ctx[EPISODE_CONTEXT_FEATURES[-1]] > 0, "Replay", "Benign")
    df["run_id"], df["view"] = np.repeat([f"r{k}" for k in range(12)], 40), EPISODE_VIEW
    assert context_columns(df) == EPISODE_CONTEXT_FEATURES and len(EPISODE_CONTEXT_FEATURES) > len(CONTEXT_FEATURES)
    res = run_protocol(df, "multiclass", BenchConfig(models=("context",), seeds=(0,), importance=False, n_threads=1))
    f1 = {s.cls: s.value for s in res.scores if s.metric == "f1" and s.model == "Context"}
    assert f1["Replay"] > 0.9, f1  # it learned from an episode context column, by name


def test_class_weights_by_frequency():
    yi = np.repeat([0, 1, 2], [400, 100, 25])
    for kind, power in (("sqrt", 0.5), ("balanced", 1.0)):
        w = class_weights(yi, kind)
        assert w[1] / w[0] == pytest.approx(4.0 ** power) and w[2] / w[0] == pytest.approx(16.0 ** power)
        assert sum(w[c] * n for c, n in zip((0, 1, 2), (400, 100, 25))) == pytest.approx(len(yi))
    assert class_weights(yi, None) is None
    with pytest.raises(ValueError, match="class_weight"):
        class_weights(yi, "inverse")


@pytest.mark.slow  # 5 s on 2 cores
def test_sqrt_weights_call_a_rare_overlapping_class_less_often():
    """A rare class that overlaps Benign: weighted by the inverse square root of its frequency it
    is predicted on fewer Benign rows than with 'balanced' weights, and the sqrt weights reach
    LightGBM (the default)."""
    rng = np.random.default_rng(0)

    def rows(n_benign, n_rare):
        X = pd.DataFrame({"Flow Duration": rng.normal(size=n_benign + n_rare),
                          "ctx_route_lonely_frac": np.r_[rng.normal(size=n_benign), rng.normal(1.0, 1.0, n_rare)]})
        return X, np.repeat(["Benign", "Wormhole"], [n_benign, n_rare])
    X, y = rows(1900, 40)
    Xt, yt = rows(2000, 0)
    est = baseline("context", n_jobs=1).fit(X, y)
    assert est.class_weight == "sqrt" and est.model_.class_weight == est.class_weight_
    assert est.class_weight_[1] / est.class_weight_[0] == pytest.approx(np.sqrt(1900 / 40))
    called = {w: (baseline("context", n_jobs=1, class_weight=w).fit(X, y).predict(Xt) == "Wormhole").sum()
              for w in ("sqrt", "balanced")}
    assert called["sqrt"] < called["balanced"], called
