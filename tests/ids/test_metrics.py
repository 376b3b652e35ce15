"""Scores over the declared label set: the same denominator for every model, stealth, PR-AUC."""

from __future__ import annotations

import numpy as np
import pytest
from sklearn.metrics import f1_score

from uavcas.ids.metrics import STEALTH, scores
from uavcas.vocabulary import STEALTH_CLASSES


def _proba(pred, classes):
    return (np.asarray(pred)[:, None] == np.asarray(classes)[None, :]).astype(float)


def _get(rows, metric, cls=""):
    return next(v for m, c, v in rows if m == metric and c == cls)


def test_macro_f1_over_the_declared_classes_whatever_is_predicted():
    declared = ["Benign", "DoS", "Wormhole"]
    y = np.array(["Benign"] * 6 + ["DoS"] * 3 + ["Wormhole"] * 3)
    classes = np.array(declared)
    # two models, same accuracy, errors spread differently: both averaged over the same 3 classes
    a = np.array(["Benign"] * 6 + ["DoS"] * 3 + ["Benign"] * 3)
    b = np.array(["Benign"] * 6 + ["Benign"] * 3 + ["Wormhole"] * 3)
    ra, rb = scores(y, _proba(a, classes), classes, declared), scores(y, _proba(b, classes), classes, declared)
    assert _get(ra, "accuracy") == _get(rb, "accuracy") == pytest.approx(0.75)
    for rows, pred in ((ra, a), (rb, b)):
        per = [_get(rows, "f1", c) for c in declared]
        assert _get(rows, "f1_macro") == pytest.approx(np.mean(per))
        assert _get(rows, "f1_macro") == pytest.approx(f1_score(y, pred, labels=declared, average="macro"))
    assert _get(rb, "f1", "DoS") == 0 and _get(rb, "support", "DoS") == 3
    assert _get(ra, "f1_macro") == pytest.approx(_get(rb, "f1_macro"))  # symmetric errors, same score


def test_class_never_trained_on_scores_zero_not_missing():
    declared = ["Benign", "DoS", "Replay"]
    y = np.array(["Benign", "DoS", "Replay", "Replay"])
    classes = np.array(["Benign", "DoS"])  # the model never saw Replay
    rows = scores(y, _proba(["Benign", "DoS", "Benign", "DoS"], classes), classes, declared)
    assert _get(rows, "recall", "Replay") == 0 and _get(rows, "f1", "Replay") == 0
    assert _get(rows, "pr_auc", "Replay") == pytest.approx(0.5)  # constant score: AP = prevalence
    assert _get(rows, "f1_macro", STEALTH) == 0  # Replay is the only stealth class declared


def test_stealth_is_the_macro_f1_of_the_stealth_classes():
    assert set(STEALTH_CLASSES) >= {"Blackhole", "Wormhole", "Replay", "Blackhole+DoS", "DDoS+Replay"}
    assert not {"Benign", "DoS", "DDoS"} & set(STEALTH_CLASSES) and len(STEALTH_CLASSES) == 16
    declared = ["Benign", "DoS", "Blackhole", "Wormhole"]
    y = np.array(declared * 5)
    pred = np.array(["Benign", "DoS", "Blackhole", "Benign"] * 5)
    rows = scores(y, _proba(pred, declared), np.array(declared), declared)
    assert _get(rows, "f1_macro", STEALTH) == pytest.approx((_get(rows, "f1", "Blackhole") + 0.0) / 2)


def test_binary_positive_class_auroc_and_pr_auc():
    declared = ["Benign", "DoS"]
    y = np.array(["Benign"] * 5 + ["DoS"] * 5)
    p_dos = np.array([0.1, 0.2, 0.3, 0.6, 0.1, 0.9, 0.8, 0.7, 0.4, 0.95])
    proba = np.c_[1 - p_dos, p_dos]
    rows = scores(y, proba, np.array(declared), declared, positive="DoS")
    # 24 of the 25 (DoS, Benign) pairs are ranked right (0.4 < 0.6 is the one wrong)
    assert _get(rows, "auroc") == pytest.approx(24 / 25) and 0 < _get(rows, "pr_auc") <= 1
