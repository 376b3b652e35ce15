"""`TorchClassifier`: a scikit-learn estimator around the PyTorch baselines of `nets.py`.

Training follows the paper's protocol: Adam (lr 1e-3), batch 128, 50 epochs by default, cross-
entropy, early stopping on the validation split: stop after `patience` (5) epochs without a lower
validation loss and keep the best epoch's weights. The validation split is the protocol's
grouped one (`fit(X, y, X_val=..., y_val=...)`); without it, a seeded stratified
`validation_fraction` of the training rows is held out. Seeded (torch.manual_seed, deterministic
algorithms, numpy-driven batch order); torch is imported lazily so the classical baselines work
without the `dl` extra.
"""

from __future__ import annotations

import copy
import os

import numpy as np
from sklearn.base import BaseEstimator, ClassifierMixin
from sklearn.utils.multiclass import check_classification_targets
from sklearn.utils.validation import check_is_fitted

DL_MISSING = "the deep baselines need PyTorch: pip install 'uavcas[dl]' (torch==2.13.0)"


def import_torch():
    try:
        import torch
    except ImportError as e:  # a clear message instead of a bare ModuleNotFoundError
        raise ImportError(DL_MISSING) from e
    return torch


def default_threads() -> int:
    """UAVCAS_THREADS if set, else the cores this process may use (2 on the dev machine).

    Why: OpenMP/torch threads busy-wait; more threads than free cores (a shared 2-core machine)
    makes training many times slower, so callers on a busy machine should pass 1.
    """
    env = os.environ.get("UAVCAS_THREADS")
    if env:
        return max(1, int(env))
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except AttributeError:
        return max(1, os.cpu_count() or 1)


class TorchClassifier(ClassifierMixin, BaseEstimator):
    def __init__(
        self, arch: str = "cnn1d", epochs: int = 50, batch_size: int = 128, lr: float = 1e-3,
        patience: int = 5, validation_fraction: float = 0.1, random_state: int | None = 0,
        n_threads: int | None = None, verbose: int = 0,
    ) -> None:
        self.arch = arch
        self.epochs = epochs
        self.batch_size = batch_size
        self.lr = lr
        self.patience = patience
        self.validation_fraction = validation_fraction
        self.random_state = random_state
        self.n_threads = n_threads
        self.verbose = verbose

    # -- helpers -------------------------------------------------------------------------
    def _setup(self):
        torch = import_torch()
        torch.set_num_threads(self.n_threads or default_threads())
        return torch

    def _holdout(self, X, yi, rng):
        if not 0 < self.validation_fraction < 1 or len(X) < 10:
            return X, yi, None, None
        from sklearn.model_selection import train_test_split

        counts = np.bincount(yi)
        strat = yi if counts[counts > 0].min() >= 2 else None
        tr, va = train_test_split(np.arange(len(X)), test_size=self.validation_fraction,
                                  random_state=int(rng.integers(2**31)), stratify=strat)
        return X[tr], yi[tr], X[va], yi[va]

    # -- estimator API -------------------------------------------------------------------
    def fit(self, X, y, X_val=None, y_val=None):
        torch = self._setup()
        from .nets import ARCHITECTURES

        if self.arch not in ARCHITECTURES:
            raise ValueError(f"unknown architecture {self.arch!r}; known: {sorted(ARCHITECTURES)}")
        X = np.asarray(X, dtype=np.float32)
        y = np.asarray(y)
        check_classification_targets(y)
        if X.ndim != 2 or len(X) != len(y) or len(X) == 0:
            raise ValueError(f"X must be 2-D with one row per label, got {X.shape} and {y.shape}")
        self.classes_ = np.unique(y)
        self.n_features_in_ = X.shape[1]
        yi = np.searchsorted(self.classes_, y)
        rng = np.random.default_rng(self.random_state)
        if X_val is None:
            X, yi, X_val, yv = self._holdout(X, yi, rng)
        else:
            X_val = np.asarray(X_val, dtype=np.float32)
            keep = np.isin(np.asarray(y_val), self.classes_)  # a val-only class cannot be scored
            X_val, yv = X_val[keep], np.searchsorted(self.classes_, np.asarray(y_val)[keep])
        seed = 0 if self.random_state is None else int(self.random_state)
        torch.manual_seed(seed)
        was_det = torch.are_deterministic_algorithms_enabled()
        torch.use_deterministic_algorithms(True)
        try:
            self._train(torch, X, yi, X_val, yv, rng)
        finally:
            torch.use_deterministic_algorithms(was_det)
        return self

    def _train(self, torch, X, yi, X_val, yv, rng) -> None:
        from .nets import ARCHITECTURES

        model = ARCHITECTURES[self.arch](X.shape[1], len(self.classes_))
        opt = torch.optim.Adam(model.parameters(), lr=self.lr)
        loss_fn = torch.nn.CrossEntropyLoss()
        xt, yt = torch.from_numpy(X), torch.from_numpy(yi.astype(np.int64))
        has_val = X_val is not None and len(X_val) > 0
        if has_val:
            xv, yvt = torch.from_numpy(np.ascontiguousarray(X_val)), torch.from_numpy(yv.astype(np.int64))
        best, best_state, bad = np.inf, None, 0
        self.history_: list[dict[str, float]] = []
        for epoch in range(self.epochs):
            model.train()
            order = torch.from_numpy(rng.permutation(len(X)))
            total = 0.0
            for start in range(0, len(X), self.batch_size):
                idx = order[start : start + self.batch_size]
                if len(idx) < 2 and len(X) >= 2:
                    continue  # BatchNorm cannot train on a batch of one
                opt.zero_grad()
                loss = loss_fn(model(xt[idx]), yt[idx])
                loss.backward()
                opt.step()
                total += float(loss.detach()) * len(idx)
            rec = {"epoch": epoch + 1, "train_loss": total / len(X)}
            if has_val:
                model.eval()
                with torch.no_grad():
                    v = float(loss_fn(model(xv), yvt))
                rec["val_loss"] = v
                if v < best - 1e-6:
                    best, best_state, bad = v, copy.deepcopy(model.state_dict()), 0
                else:
                    bad += 1
            self.history_.append(rec)
            if self.verbose:
                print(f"[{self.arch}] {rec}")
            if has_val and bad >= self.patience:
                break
        if best_state is not None:
            model.load_state_dict(best_state)
        model.eval()
        self.model_ = model
        self.n_epochs_ = len(self.history_)

    def predict_proba(self, X) -> np.ndarray:
        check_is_fitted(self, "model_")
        torch = self._setup()
        X = np.asarray(X, dtype=np.float32)
        if X.ndim != 2 or X.shape[1] != self.n_features_in_:
            raise ValueError(f"X has {X.shape[-1] if X.ndim else 0} features, expected {self.n_features_in_}")
        out = []
        with torch.no_grad():
            for start in range(0, len(X), 8192):
                logits = self.model_(torch.from_numpy(X[start : start + 8192]))
                out.append(torch.softmax(logits, dim=1).numpy())
        return np.concatenate(out) if out else np.empty((0, len(self.classes_)))

    def predict(self, X) -> np.ndarray:
        return self.classes_[np.argmax(self.predict_proba(X), axis=1)]

    def __sklearn_tags__(self):
        tags = super().__sklearn_tags__()
        tags.non_deterministic = False
        return tags
