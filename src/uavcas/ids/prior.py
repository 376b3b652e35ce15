"""Undoing the training cap's class prior, for the protocols whose metric weighs the natural one.

`--train-cap N` keeps at most N training flows per (run, class): a flood run's thousands of
near-identical SYN flows become N, so fits stay cheap and every run and class is kept. It also
moves the class prior the model learns. In the 5-tuple view's binary protocol the capped
training flows are 24 % DoS against 98 % of the uncapped training split, and the test split is
98 % DoS: Context ranked the test flows almost perfectly (AUROC 0.99998) yet, at the capped
prior, called 2 % of the DoS flows Benign (weighted F1 0.957 over five seeds).

A classifier's posteriors move with the prior by Bayes' rule (Saerens, Latinne and
Decaestecker, "Adjusting the outputs of a classifier to new a priori probabilities", Neural
Computation 14(1), 2002): p'(c|x) is proportional to p(c|x) * pi(c) / pi_cap(c), with pi the
class frequencies of the uncapped training split (never the test split's) and pi_cap those of
the rows the model was fitted on. The binary and OOD protocols, scored by weighted F1 and by
attack-vs-Benign, take that correction; the multiclass and cross-condition protocols, scored by
macro-F1 over classes of very different sizes, keep the capped, near-balanced prior on purpose.
"""

from __future__ import annotations

import numpy as np


def prior_ratio(y_full: np.ndarray, y_fitted: np.ndarray, classes) -> np.ndarray:
    """pi(c) / pi_cap(c) per class of `classes` (the model's `classes_` order): the uncapped
    training rows' class frequencies over the fitted rows'. 1 for a class absent from either."""
    full = np.array([np.mean(y_full == c) for c in classes], dtype=np.float64)
    fitted = np.array([np.mean(y_fitted == c) for c in classes], dtype=np.float64)
    ok = (full > 0) & (fitted > 0)
    return np.where(ok, full / np.where(ok, fitted, 1.0), 1.0)


def reweight(proba: np.ndarray, ratio: np.ndarray) -> np.ndarray:
    """Posteriors at the uncapped prior: each column times its class's ratio, rows renormalised."""
    p = np.asarray(proba, dtype=np.float64) * ratio
    total = p.sum(axis=1, keepdims=True)
    return np.divide(p, total, out=np.full_like(p, 1.0 / p.shape[1]), where=total > 0)
