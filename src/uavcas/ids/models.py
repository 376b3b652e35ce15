"""The ten baselines by name: `baseline(name, **params)` returns a fresh, unfitted scikit-learn
classifier with the paper's settings, `params` overriding them (`set_params` names).

Classical (scikit-learn / LightGBM), as in Hassler et al. 2024 (LR, SGD, RF, MLP) and Silva et
al. 2023 (LightGBM); deep ones are `TorchClassifier`s (see nets.py for the architectures). The
models that early-stop (MLP, LightGBM, the five networks) take the protocol's grouped validation
split: `fit(X, y, X_val=..., y_val=...)` (`accepts_validation`).

Beyond the ten, the context-aware detector and its ablation (`CONTEXT_MODELS`, `ids/context.py`):
`context` learns from the flow features and the dataset's `ctx_*` context columns,
`context-flow` from the flow features only, `context-only` from the context columns only,
`context-joint` from both in one model instead of the context's two stages.
"""

from __future__ import annotations

from collections.abc import Callable

from sklearn.base import BaseEstimator

from .base import EarlyStoppingClassifier
from .classical import GroupedMLPClassifier, LightGBMClassifier
from .context import VARIANTS, ContextClassifier
from .torch_estimator import TorchClassifier, default_threads

CLASSICAL = ("lr", "sgd", "rf", "mlp", "lightgbm")
DEEP = ("cnn1d", "lstm", "convnet", "tinyml", "cnn_bilstm")
MODELS: tuple[str, ...] = CLASSICAL + DEEP  # the ten baselines
CONTEXT_MODELS: tuple[str, ...] = tuple(VARIANTS)  # context, context-joint, context-flow, context-only
ALL_MODELS: tuple[str, ...] = MODELS + CONTEXT_MODELS
TREES = ("rf", "lightgbm") + CONTEXT_MODELS  # permutation importance is computed for these
DISPLAY: dict[str, str] = {
    "lr": "LR", "sgd": "SGD", "rf": "RF", "mlp": "MLP", "lightgbm": "LightGBM", "cnn1d": "1D-CNN",
    "lstm": "LSTM", "convnet": "ConvNet", "tinyml": "TinyML", "cnn_bilstm": "CNN-BiLSTM",
    "context": "Context", "context-joint": "Context-joint", "context-flow": "Context-flow", "context-only": "Context-only",
}
PATIENCE = 5
# the parameter each model calls its epoch budget and its thread count
EPOCH_PARAM = {"mlp": "max_iter", **{d: "epochs" for d in DEEP}}
THREAD_PARAM = {"rf": "n_jobs", "lightgbm": "n_jobs", **{d: "n_threads" for d in DEEP}, **{c: "n_jobs" for c in CONTEXT_MODELS}}


def _lr() -> BaseEstimator:
    from sklearn.linear_model import LogisticRegression

    return LogisticRegression(max_iter=1000, random_state=0)


def _sgd() -> BaseEstimator:
    from sklearn.linear_model import SGDClassifier

    # log loss so that predict_proba exists (AUROC and PR-AUC need scores)
    return SGDClassifier(loss="log_loss", max_iter=1000, tol=1e-4, random_state=0)


def _rf() -> BaseEstimator:
    from sklearn.ensemble import RandomForestClassifier

    return RandomForestClassifier(n_estimators=100, random_state=0)


_FACTORIES: dict[str, Callable[[], BaseEstimator]] = {
    "lr": _lr,
    "sgd": _sgd,
    "rf": _rf,
    "mlp": lambda: GroupedMLPClassifier(max_iter=50, n_iter_no_change=PATIENCE),
    "lightgbm": lambda: LightGBMClassifier(n_estimators=200, learning_rate=0.1, num_leaves=31),
    **{d: (lambda d=d: TorchClassifier(arch=d, epochs=50, patience=PATIENCE)) for d in DEEP},
    **{c: (lambda kw=kw: ContextClassifier(**kw)) for c, kw in VARIANTS.items()},
}


def baseline(name: str, **params) -> BaseEstimator:
    """A fresh, unfitted estimator for model `name` (one of ALL_MODELS: the ten baselines and the
    context models), e.g. `baseline("rf", n_estimators=50)`; unknown names or parameters raise
    ValueError."""
    key = name.strip().lower()
    if key not in _FACTORIES:
        raise ValueError(f"unknown model {name!r}; known: {', '.join(ALL_MODELS)}")
    return _FACTORIES[key]().set_params(**params)


def make_model(name: str, random_state: int = 0, epochs: int = 50, n_threads: int | None = None,
               device: str = "auto") -> BaseEstimator:
    """`baseline(name)` with the benchmark's common knobs mapped to each model's own parameter
    (`device` reaches the torch models only: the others run on the CPU)."""
    params: dict[str, object] = {"random_state": random_state}
    if name in DEEP:
        params["device"] = device
    if name in EPOCH_PARAM:
        params[EPOCH_PARAM[name]] = epochs
    if name in THREAD_PARAM:
        params[THREAD_PARAM[name]] = n_threads or default_threads()
    return baseline(name, **params)


def uses_context(name: str) -> bool:
    """Whether the protocols give model `name` the context columns (as a named frame)."""
    return name in CONTEXT_MODELS


def accepts_validation(est: BaseEstimator) -> bool:
    return isinstance(est, EarlyStoppingClassifier)


def fit_model(est: BaseEstimator, X, y, X_val=None, y_val=None) -> BaseEstimator:
    """Fit, giving the protocol's (grouped) validation split to the models that early-stop on it."""
    if accepts_validation(est) and X_val is not None and len(X_val):
        return est.fit(X, y, X_val=X_val, y_val=y_val)
    return est.fit(X, y)
