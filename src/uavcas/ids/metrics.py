"""Scores of one fitted model on one test set, over the protocol's DECLARED label set.

Averages run over the declared classes only (`labels=declared`): a class a model predicts but the
protocol does not declare cannot change the mean, and the split guarantees every declared class
is in the test set, so a macro-F1 is always a mean over the same classes for every model.

Rows are (metric, class, value), class "" for overall metrics:
- accuracy, f1_macro, f1_weighted, pr_auc_macro;
- per declared class: precision, recall, f1, support (test flows), pr_auc (average precision of
  the one-vs-rest score; the score is 0 for a class the model was not trained on);
- f1_macro with class "stealth": the macro-F1 over the declared classes holding a stealth family
  (`vocabulary.STEALTH_CLASSES`), when there are any;
- with `positive` (binary protocols): auroc and pr_auc of that class's score.
"""

from __future__ import annotations

import numpy as np
from sklearn.metrics import average_precision_score, confusion_matrix, precision_recall_fscore_support, roc_auc_score

from uavcas.vocabulary import STEALTH_CLASSES

STEALTH = "stealth"


def class_scores(proba: np.ndarray, model_classes, cls: str) -> np.ndarray:
    """The model's probability of `cls` per row (0 when it never saw the class)."""
    where = np.flatnonzero(np.asarray(model_classes) == cls)
    return proba[:, where[0]] if len(where) else np.zeros(len(proba))


def auroc(y_pos: np.ndarray, score: np.ndarray) -> float:
    return float(roc_auc_score(y_pos, score)) if len(np.unique(y_pos)) == 2 else float("nan")


def pr_auc(y_pos: np.ndarray, score: np.ndarray) -> float:
    return float(average_precision_score(y_pos, score)) if y_pos.any() else float("nan")


def scores(y_true, proba: np.ndarray, model_classes, declared: list[str],
           positive: str | None = None) -> list[tuple[str, str, float]]:
    y_true = np.asarray(y_true)
    model_classes = np.asarray(model_classes)
    pred = model_classes[proba.argmax(1)]
    p, r, f, s = precision_recall_fscore_support(y_true, pred, labels=declared, zero_division=0)
    _, _, fw, _ = precision_recall_fscore_support(y_true, pred, labels=declared, average="weighted", zero_division=0)
    aps = [pr_auc(y_true == c, class_scores(proba, model_classes, c)) for c in declared]
    rows = [("accuracy", "", float(np.mean(y_true == pred))), ("f1_macro", "", float(np.mean(f))),
            ("f1_weighted", "", float(fw)),
            ("pr_auc_macro", "", float(np.nanmean(aps)) if not np.all(np.isnan(aps)) else np.nan)]
    for i, c in enumerate(declared):
        rows += [("precision", c, float(p[i])), ("recall", c, float(r[i])), ("f1", c, float(f[i])),
                 ("support", c, float(s[i])), ("pr_auc", c, aps[i])]
    stealth = [float(f[i]) for i, c in enumerate(declared) if c in STEALTH_CLASSES]
    if stealth:
        rows.append(("f1_macro", STEALTH, float(np.mean(stealth))))
    if positive is not None:
        score = class_scores(proba, model_classes, positive)
        rows += [("auroc", "", auroc(y_true == positive, score)), ("pr_auc", "", pr_auc(y_true == positive, score))]
    return rows


def confusion(y_true, pred, declared: list[str]) -> np.ndarray:
    """Counts, rows = true class, columns = predicted class, both in declared order."""
    return confusion_matrix(np.asarray(y_true), np.asarray(pred), labels=declared)
