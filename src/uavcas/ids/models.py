"""The ten baselines by name, each a scikit-learn estimator (fit/predict/predict_proba/classes_).

Classical (scikit-learn / LightGBM), as in Hassler et al. 2024 (LR, SGD, RF, MLP) and Silva et
al. 2023 (LightGBM); deep ones are `TorchClassifier`s (see nets.py for the architectures).
The MLP follows the paper's neural protocol too: Adam 1e-3, batch 128, `epochs` iterations,
early stopping (sklearn's own: a stratified 10% of the training rows, patience 5).
"""

from __future__ import annotations

import warnings

import numpy as np
from sklearn.base import BaseEstimator

from .torch_estimator import TorchClassifier, default_threads

CLASSICAL = ("lr", "sgd", "rf", "mlp", "lightgbm")
DEEP = ("cnn1d", "lstm", "convnet", "tinyml", "cnn_bilstm")
MODELS: tuple[str, ...] = CLASSICAL + DEEP
DISPLAY: dict[str, str] = {
    "lr": "LR", "sgd": "SGD", "rf": "RF", "mlp": "MLP", "lightgbm": "LightGBM", "cnn1d": "1D-CNN",
    "lstm": "LSTM", "convnet": "ConvNet", "tinyml": "TinyML", "cnn_bilstm": "CNN-BiLSTM",
}
PATIENCE = 5


def make_model(name: str, random_state: int = 0, epochs: int = 50, n_threads: int | None = None) -> BaseEstimator:
    """A fresh, unfitted estimator for baseline `name` (see MODELS)."""
    threads = n_threads or default_threads()
    if name == "lr":
        from sklearn.linear_model import LogisticRegression

        return LogisticRegression(max_iter=1000, random_state=random_state)
    if name == "sgd":
        from sklearn.linear_model import SGDClassifier

        # log loss so that predict_proba exists (AUROC needs scores)
        return SGDClassifier(loss="log_loss", max_iter=1000, tol=1e-4, random_state=random_state)
    if name == "rf":
        from sklearn.ensemble import RandomForestClassifier

        return RandomForestClassifier(n_estimators=100, n_jobs=threads, random_state=random_state)
    if name == "mlp":
        from sklearn.neural_network import MLPClassifier

        return MLPClassifier(hidden_layer_sizes=(128, 64), solver="adam", learning_rate_init=1e-3,
                             batch_size=128, max_iter=epochs, early_stopping=True,
                             validation_fraction=0.1, n_iter_no_change=PATIENCE, random_state=random_state)
    if name == "lightgbm":
        from lightgbm import LGBMClassifier

        return LGBMClassifier(n_estimators=200, learning_rate=0.1, num_leaves=31, n_jobs=threads,
                              random_state=random_state, deterministic=True, verbose=-1)
    if name in DEEP:
        return TorchClassifier(arch=name, epochs=epochs, patience=PATIENCE, random_state=random_state, n_threads=threads)
    raise ValueError(f"unknown model {name!r}; known: {', '.join(MODELS)}")


def fit_model(est: BaseEstimator, X, y, X_val=None, y_val=None) -> BaseEstimator:
    """Fit, giving the protocol's (grouped) validation split to the models that early-stop on it."""
    if isinstance(est, TorchClassifier) and X_val is not None and len(X_val):
        return est.fit(X, y, X_val=X_val, y_val=y_val)
    if type(est).__name__ == "LGBMClassifier" and X_val is not None and len(X_val):
        import lightgbm as lgb

        keep = np.isin(y_val, np.unique(y))
        if keep.any():
            xv, yv = X_val[keep], np.asarray(y_val)[keep]
            cb = [lgb.early_stopping(20, verbose=False)]
            # eval_set is deprecated in 4.7 for eval_X/eval_y, but only eval_set label-encodes
            # string classes; keep it and silence the deprecation
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                return est.fit(X, y, eval_set=[(xv, yv)], callbacks=cb)
    return est.fit(X, y)
