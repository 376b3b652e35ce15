"""The two classical baselines that early-stop, as `EarlyStoppingClassifier`s so that they stop
on the protocol's grouped validation split (runs never trained on), not on random rows:

- `GroupedMLPClassifier`: scikit-learn's MLP (Adam 1e-3, batch 128, two hidden layers 128-64 as
  in Hassler et al. 2024), trained epoch by epoch (`partial_fit`); after each epoch the log-loss
  on the validation split decides; stop after `n_iter_no_change` epochs without improvement and
  keep the best epoch's weights (sklearn's own early stopping holds out random training rows).
- `LightGBMClassifier`: LightGBM (Silva et al. 2023) boosting rounds, stopped when the
  validation log-loss has not improved for `early_stopping_rounds` rounds.
"""

from __future__ import annotations

import lightgbm as lgb
import numpy as np
from sklearn.metrics import log_loss
from sklearn.neural_network import MLPClassifier

from .base import EarlyStoppingClassifier
from .torch_estimator import default_threads


class GroupedMLPClassifier(EarlyStoppingClassifier):
    def __init__(
        self, hidden_layer_sizes: tuple[int, ...] = (128, 64), alpha: float = 1e-4, batch_size: int = 128,
        learning_rate_init: float = 1e-3, max_iter: int = 50, n_iter_no_change: int = 5,
        validation_fraction: float = 0.1, random_state: int | None = 0,
    ) -> None:
        self.hidden_layer_sizes = hidden_layer_sizes
        self.alpha = alpha
        self.batch_size = batch_size
        self.learning_rate_init = learning_rate_init
        self.max_iter = max_iter
        self.n_iter_no_change = n_iter_no_change
        self.validation_fraction = validation_fraction
        self.random_state = random_state

    def _fit_core(self, X, yi, X_val, yv, rng) -> None:
        labels = np.arange(len(self.classes_))
        # a RandomState instance (not an int) so that each partial_fit call draws a new batch order
        state = np.random.RandomState(None if self.random_state is None else int(self.random_state))
        net = MLPClassifier(hidden_layer_sizes=self.hidden_layer_sizes, solver="adam", alpha=self.alpha,
                            batch_size=min(self.batch_size, len(X)), learning_rate_init=self.learning_rate_init,
                            max_iter=1, shuffle=True, random_state=state)
        best, best_w, bad = np.inf, None, 0
        self.validation_loss_: list[float] = []
        for _ in range(self.max_iter):
            net.partial_fit(X, yi, classes=labels)
            if X_val is None:
                continue
            v = log_loss(yv, net.predict_proba(X_val), labels=labels)
            self.validation_loss_.append(v)
            if v < best - 1e-6:
                best, best_w, bad = v, ([c.copy() for c in net.coefs_], [b.copy() for b in net.intercepts_]), 0
            else:
                bad += 1
                if bad >= self.n_iter_no_change:
                    break
        if best_w is not None:
            net.coefs_, net.intercepts_ = best_w
        self.n_iter_ = net.n_iter_ if X_val is None else len(self.validation_loss_)
        self.loss_curve_ = list(net.loss_curve_)
        self.model_ = net

    def _proba_core(self, X) -> np.ndarray:
        return self.model_.predict_proba(X)


class LightGBMClassifier(EarlyStoppingClassifier):
    def __init__(
        self, n_estimators: int = 200, learning_rate: float = 0.1, num_leaves: int = 31,
        early_stopping_rounds: int = 20, validation_fraction: float = 0.0, random_state: int | None = 0,
        n_jobs: int | None = None,
    ) -> None:
        self.n_estimators = n_estimators
        self.learning_rate = learning_rate
        self.num_leaves = num_leaves
        self.early_stopping_rounds = early_stopping_rounds
        self.validation_fraction = validation_fraction
        self.random_state = random_state
        self.n_jobs = n_jobs

    def _fit_core(self, X, yi, X_val, yv, rng) -> None:
        model = self._boost(X, yi, X_val, yv)
        self.model_ = model
        self.n_iter_ = int(model.best_iteration_ or model.n_estimators_)
        self.feature_importances_ = model.feature_importances_

    def _boost(self, X, yi, X_val, yv, init_score=None, val_init_score=None):
        """One LightGBM model, early-stopped on (X_val, yv) when given; boosting starts from
        `init_score` (raw scores, and `val_init_score` on the validation rows) when given."""
        params = self._lgbm_params()
        model = lgb.LGBMClassifier(**params)
        kw = {} if init_score is None else {"init_score": init_score}
        if X_val is not None:
            kw.update(eval_X=X_val, eval_y=yv,
                      callbacks=[lgb.early_stopping(self.early_stopping_rounds, verbose=False)])
            if val_init_score is not None:
                kw["eval_init_score"] = [val_init_score]
            if params.get("class_weight") is not None:  # stop on the loss the model is trained for
                kw["eval_class_weight"] = [params["class_weight"]]
        model.fit(X, yi, **kw)
        return model

    def _lgbm_params(self) -> dict:
        return dict(n_estimators=self.n_estimators, learning_rate=self.learning_rate, num_leaves=self.num_leaves,
                    n_jobs=self.n_jobs or default_threads(), random_state=self.random_state, deterministic=True,
                    verbose=-1)

    def _proba_core(self, X) -> np.ndarray:
        return self.model_.predict_proba(X)
