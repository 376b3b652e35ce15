"""`TorchClassifier`: a scikit-learn estimator around a PyTorch network (`network`: a class or
callable `(n_features, n_classes) -> torch.nn.Module`, e.g. one of `nets.py`; each deep detector
of `uavcas.ids.detectors` names its own).

Training follows the paper's protocol: Adam (lr 1e-3), batch 128, 50 epochs by default, cross-
entropy, early stopping on the validation split: stop after `patience` (5) epochs without a lower
validation loss and keep the best epoch's weights. The validation split is the protocol's
grouped one (`fit(X, y, X_val=..., y_val=...)`); input checks, the fallback holdout and the
one-class case are `EarlyStoppingClassifier`'s. Seeded (torch.manual_seed, deterministic
algorithms, numpy-driven batch order); torch is imported lazily so the classical baselines work
without the `dl` extra.

`device`: "auto" trains on CUDA when torch sees a GPU and on the CPU otherwise ("cpu" and "cuda"
force one); `device_` records where the model was fitted. Deterministic CUDA matrix products need
cuBLAS's fixed workspace (CUBLAS_WORKSPACE_CONFIG, set here when the caller did not); the seeded
results of a GPU fit are reproducible on that GPU, not bit-equal to a CPU fit.
"""

from __future__ import annotations

import copy
import os
from collections.abc import Callable
from typing import Any

import numpy as np

from uavcas.vocabulary import TORCH_DEVICES

from .base import EarlyStoppingClassifier

DL_MISSING = "the deep baselines need PyTorch: pip install 'uavcas[dl]' (torch==2.13.0)"
DEVICES = TORCH_DEVICES
PREDICT_BATCH = 8192


def import_torch():
    try:
        import torch  # deferred: the optional `dl` extra; the classical detectors share this module's base
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


class TorchClassifier(EarlyStoppingClassifier):
    _dtype = np.float32

    def __init__(
        self, network: Callable[[int, int], Any] | None = None, epochs: int = 50, batch_size: int = 128,
        lr: float = 1e-3, patience: int = 5, validation_fraction: float = 0.1, random_state: int | None = 0,
        n_threads: int | None = None, device: str = "auto", verbose: int = 0,
    ) -> None:
        self.network = network
        self.epochs = epochs
        self.batch_size = batch_size
        self.lr = lr
        self.patience = patience
        self.validation_fraction = validation_fraction
        self.random_state = random_state
        self.n_threads = n_threads
        self.device = device
        self.verbose = verbose

    def _torch(self):
        torch = import_torch()
        torch.set_num_threads(self.n_threads or default_threads())
        return torch

    def _device(self, torch) -> str:
        """The device to train on (`fit` has checked the name before any work)."""
        if self.device == "cuda" and not torch.cuda.is_available():
            raise ValueError("device 'cuda': torch sees no CUDA GPU (use auto or cpu)")
        dev = "cpu" if self.device == "cpu" or not torch.cuda.is_available() else "cuda"
        if dev == "cuda":
            os.environ.setdefault("CUBLAS_WORKSPACE_CONFIG", ":4096:8")
        return dev

    def fit(self, X, y, X_val=None, y_val=None):
        if not callable(self.network):
            raise ValueError(f"network: expected a torch.nn.Module class or builder, got {self.network!r}")
        if self.device not in DEVICES:
            raise ValueError(f"device {self.device!r}: expected one of {', '.join(DEVICES)}")
        return super().fit(X, y, X_val=X_val, y_val=y_val)

    def _fit_core(self, X, yi, X_val, yv, rng) -> None:
        torch = self._torch()
        torch.manual_seed(0 if self.random_state is None else int(self.random_state))
        was_det = torch.are_deterministic_algorithms_enabled()
        torch.use_deterministic_algorithms(True)
        try:
            self._train(torch, X, yi, X_val, yv, rng)
        finally:
            torch.use_deterministic_algorithms(was_det)

    def _train(self, torch, X, yi, X_val, yv, rng) -> None:
        dev = self.device_ = self._device(torch)
        model = self.network(X.shape[1], len(self.classes_)).to(dev)
        opt = torch.optim.Adam(model.parameters(), lr=self.lr)
        loss_fn = torch.nn.CrossEntropyLoss()
        # copies: the caller's array may be read-only (memory-mapped); on the device once, not per batch
        xt, yt = torch.tensor(X, device=dev), torch.tensor(yi.astype(np.int64), device=dev)
        has_val = X_val is not None
        if has_val:
            xv, yvt = torch.tensor(X_val, device=dev), torch.tensor(yv.astype(np.int64), device=dev)
        best, best_state, bad = np.inf, None, 0
        self.history_: list[dict[str, float]] = []
        for epoch in range(self.epochs):
            model.train()
            order = torch.from_numpy(rng.permutation(len(X))).to(dev)
            total = torch.zeros((), dtype=torch.float64, device=dev)  # summed on the device: no sync per batch
            for start in range(0, len(X), self.batch_size):
                idx = order[start : start + self.batch_size]
                if len(idx) < 2:
                    continue  # BatchNorm cannot train on a batch of one
                opt.zero_grad()
                loss = loss_fn(model(xt[idx]), yt[idx])
                loss.backward()
                opt.step()
                total += loss.detach().double() * len(idx)
            rec = {"epoch": epoch + 1, "train_loss": float(total) / len(X)}
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
                print(f"[{getattr(self.network, '__name__', self.network)}] {rec}")
            if has_val and bad >= self.patience:
                break
        if best_state is not None:
            model.load_state_dict(best_state)
        model.eval()
        self.model_ = model
        self.n_iter_ = self.n_epochs_ = len(self.history_)

    def _proba_core(self, X) -> np.ndarray:
        torch = self._torch()
        out = []
        with torch.no_grad():
            for start in range(0, len(X), PREDICT_BATCH):
                logits = self.model_(torch.tensor(X[start : start + PREDICT_BATCH], device=self.device_))
                out.append(torch.softmax(logits, dim=1).cpu().numpy().astype(np.float64))
        return np.concatenate(out)
