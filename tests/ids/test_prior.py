"""The training cap's prior, undone for the binary and OOD protocols (`uavcas.ids.prior`)."""

from __future__ import annotations

import numpy as np
from sklearn.linear_model import LogisticRegression

from uavcas.ids.prior import prior_ratio, reweight
from uavcas.ids.protocols import PRIOR_NOTE, BenchConfig, run_protocol


def _overlapping(n: int, attack_share: float, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    y = np.where(rng.random(n) < attack_share, "DoS", "Benign").astype(object)
    x = rng.normal(np.where(y == "DoS", 1.0, -1.0), 1.0).reshape(-1, 1)
    return x, y


def test_reweighting_restores_the_decisions_of_a_fit_at_the_natural_prior():
    rng = np.random.default_rng(0)
    x, y = _overlapping(40_000, 0.95, rng)
    xt, yt = _overlapping(40_000, 0.95, rng)
    # a capped fit: as many Benign as DoS rows, the way `--train-cap` levels a flood run
    ben, dos = np.flatnonzero(y == "Benign"), np.flatnonzero(y == "DoS")
    capped = np.concatenate([ben, rng.choice(dos, ben.shape[0], replace=False)])
    m = LogisticRegression().fit(x[capped], y[capped])
    raw = m.classes_[m.predict_proba(xt).argmax(1)]
    ratio = prior_ratio(y, y[capped], m.classes_)
    assert np.allclose(ratio, [0.05 / 0.5, 0.95 / 0.5], rtol=0.05)
    fixed = m.classes_[reweight(m.predict_proba(xt), ratio).argmax(1)]
    full = LogisticRegression().fit(x, y)
    natural = full.classes_[full.predict_proba(xt).argmax(1)]
    assert (fixed == yt).mean() > (raw == yt).mean() + 0.05  # the capped prior costs ~7 points here
    assert abs((fixed == yt).mean() - (natural == yt).mean()) < 0.005
    assert (fixed != natural).mean() < 0.01


def test_reweight_keeps_rows_summing_to_one_and_absent_classes_neutral():
    p = reweight(np.array([[0.5, 0.5], [0.0, 0.0]]), np.array([3.0, 1.0]))
    assert np.allclose(p, [[0.75, 0.25], [0.5, 0.5]])
    assert prior_ratio(np.array(["a", "b"]), np.array(["a", "a"]), ["a", "b", "c"]).tolist() == [0.5, 1.0, 1.0]


def test_binary_and_ood_score_at_the_uncapped_prior_multiclass_does_not(synth_df):
    cfg = BenchConfig(models=("lr",), seeds=(0,), train_cap=3, importance=False)
    assert PRIOR_NOTE in run_protocol(synth_df, "binary", cfg).notes
    assert PRIOR_NOTE not in run_protocol(synth_df, "multiclass", cfg).notes
    uncapped = BenchConfig(models=("lr",), seeds=(0,), importance=False)
    assert PRIOR_NOTE not in run_protocol(synth_df, "binary", uncapped).notes
