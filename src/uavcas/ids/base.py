"""`EarlyStoppingClassifier`: what the early-stopping baselines (MLP, LightGBM, the five torch
networks) share so that each is a true scikit-learn classifier.

- Input checked the scikit-learn way (`validate_data`: 2-D, finite, non-empty, no sparse input,
  `n_features_in_`, feature names); targets through `check_classification_targets`.
- `fit(X, y, X_val=None, y_val=None)`: the protocols pass their grouped validation split (runs
  never seen in training) and the model early-stops on it. Without one, a seeded, stratified
  `validation_fraction` of the training rows is held out (per class, never a class's last row),
  or nothing when the data is too small to spare rows.
- A single class is fitted as a constant predictor (probability 1 for that class); there is
  nothing to learn, and a protocol never trains on one class anyway.
- `predict` before `fit` raises NotFittedError.

Subclasses implement `_fit_core(X, yi, X_val, yi_val, rng)` (integer-coded classes 0..C-1) and
`_proba_core(X)`.
"""

from __future__ import annotations

import numpy as np
from sklearn.base import BaseEstimator, ClassifierMixin
from sklearn.utils.multiclass import check_classification_targets
from sklearn.utils.validation import check_is_fitted, validate_data

MIN_HOLDOUT_ROWS = 10  # below this, no row is spared for validation
PATIENCE = 5  # the paper's early stopping: epochs without a lower validation loss before stopping


def stratified_holdout(yi: np.ndarray, fraction: float,
                       rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray] | None:
    """(train, val) row indices: round(fraction * count) rows of each class with >= 2 rows go to
    validation, never a class's last row; None when nothing would be held out."""
    if not 0 < fraction < 1 or len(yi) < MIN_HOLDOUT_ROWS:
        return None
    val = []
    for c in np.unique(yi):
        rows = np.flatnonzero(yi == c)
        k = min(int(round(fraction * len(rows))), len(rows) - 1)
        if k > 0:
            val.append(rng.choice(rows, k, replace=False))
    if not val:
        return None
    v = np.sort(np.concatenate(val))
    return np.setdiff1d(np.arange(len(yi)), v), v


class EarlyStoppingClassifier(ClassifierMixin, BaseEstimator):
    """Base class; see the module docstring. Parameters read here: `validation_fraction`,
    `random_state` (subclasses declare them in their own __init__)."""

    _dtype = np.float64

    def fit(self, X, y, X_val=None, y_val=None):
        X, y = validate_data(self, X, y, dtype=self._dtype)
        check_classification_targets(y)
        if X.shape[0] < 2:
            raise ValueError(f"{type(self).__name__} needs at least 2 samples, got n_samples = {X.shape[0]}")
        self.classes_, yi = np.unique(y, return_inverse=True)
        rng = np.random.default_rng(self.random_state)
        if len(self.classes_) == 1:
            self.n_iter_ = 0
            return self
        xv = yv = None
        if X_val is not None and y_val is not None and len(X_val):
            xv = validate_data(self, X_val, reset=False, dtype=self._dtype)
            y_val = np.asarray(y_val)
            keep = np.isin(y_val, self.classes_)  # a class seen only in validation cannot be scored
            xv, yv = xv[keep], np.searchsorted(self.classes_, y_val[keep])
            if not len(xv):
                xv = yv = None
        else:
            split = stratified_holdout(yi, self.validation_fraction, rng)
            if split is not None:
                tr, va = split
                X, yi, xv, yv = X[tr], yi[tr], X[va], yi[va]
        self._fit_core(X, yi, xv, yv, rng)
        return self

    def predict_proba(self, X) -> np.ndarray:
        check_is_fitted(self, "classes_")
        X = validate_data(self, X, reset=False, dtype=self._dtype)
        if len(self.classes_) == 1:
            return np.ones((X.shape[0], 1))
        return self._proba_core(X)

    def predict(self, X) -> np.ndarray:
        proba = self.predict_proba(X)  # first: it raises NotFittedError before classes_ is read
        return self.classes_[np.argmax(proba, axis=1)]

    def _fit_core(self, X, yi, X_val, yi_val, rng) -> None:  # pragma: no cover - abstract
        raise NotImplementedError

    def _proba_core(self, X) -> np.ndarray:  # pragma: no cover - abstract
        raise NotImplementedError

    def __sklearn_tags__(self):
        tags = super().__sklearn_tags__()
        tags.non_deterministic = False  # seeded: same random_state, same model
        return tags


def accepts_validation(est: BaseEstimator) -> bool:
    return isinstance(est, EarlyStoppingClassifier)


def fit_model(est: BaseEstimator, X, y, X_val=None, y_val=None) -> BaseEstimator:
    """Fit, giving the protocol's (grouped) validation split to the models that early-stop on it."""
    if accepts_validation(est) and X_val is not None and len(X_val):
        return est.fit(X, y, X_val=X_val, y_val=y_val)
    return est.fit(X, y)
