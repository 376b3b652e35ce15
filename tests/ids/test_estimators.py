"""Estimator contract of every baseline: `baseline(name, **params)`, fit/predict/predict_proba,
classes_, Pipeline, clone, same seed -> same model, early stopping on the given validation split."""

from __future__ import annotations

import importlib.util
import sys

import numpy as np
import pytest
from sklearn.base import clone
from sklearn.metrics import log_loss
from sklearn.pipeline import make_pipeline
from sklearn.preprocessing import StandardScaler

from uavcas.ids import baseline, baselines, detectors
from uavcas.ids.classical import GroupedMLPClassifier, LightGBMClassifier
from uavcas.ids.detectors import make_model
from uavcas.ids.torch_estimator import DL_MISSING, TorchClassifier, import_torch

HAS_TORCH = importlib.util.find_spec("torch") is not None
NEEDS_TORCH = pytest.mark.skipif(not HAS_TORCH, reason="PyTorch not installed (pip install '.[dl]')")
ALL = [pytest.param(s.name, marks=NEEDS_TORCH) if s.needs_torch else s.name for s in baselines()]
DEEP_P = [pytest.param(s.name, marks=NEEDS_TORCH) for s in detectors() if s.needs_torch]


def _data(n=240, seed=0):
    rng = np.random.default_rng(seed)
    z = rng.normal(size=(n, 47))
    y = np.array(["Benign", "DoS", "Replay"])[(z[:, 0] > 0).astype(int) + (z[:, 1] > 0.5)]
    x = (z * np.geomspace(1, 1e4, 47)).astype(np.float32)  # raw flow-like scales
    return x, y


def _model(name, seed=0):
    return make_model(name, random_state=seed, epochs=2, n_threads=1)


@pytest.mark.parametrize("name", ALL)
def test_contract(name):
    x, y = _data()
    est = _model(name)
    assert est.fit(x[:200], y[:200]) is est
    assert list(est.classes_) == ["Benign", "DoS", "Replay"]
    p = est.predict_proba(x[200:])
    assert p.shape == (40, 3) and np.allclose(p.sum(1), 1, atol=1e-5)
    pred = est.predict(x[200:])
    assert pred.shape == (40,) and set(pred) <= set(est.classes_)
    c = clone(est)
    assert not hasattr(c, "classes_") and c.get_params() == est.get_params()


@pytest.mark.parametrize("name", ALL)
def test_pipeline_with_scaler_and_reproducible(name):
    x, y = _data(seed=1)
    p1 = make_pipeline(StandardScaler(), _model(name, seed=5)).fit(x, y).predict_proba(x)
    p2 = make_pipeline(StandardScaler(), _model(name, seed=5)).fit(x, y).predict_proba(x)
    np.testing.assert_allclose(p1, p2, rtol=0, atol=1e-6)


@pytest.mark.parametrize("name", DEEP_P)
def test_deep_early_stopping_uses_given_validation(name):
    x, y = _data(seed=2)
    est = baseline(name, epochs=3, patience=1, n_threads=1).fit(x[:200], y[:200], X_val=x[200:], y_val=y[200:])
    assert 1 <= est.n_epochs_ <= 3 and all("val_loss" in h for h in est.history_)


@NEEDS_TORCH
def test_device_auto_trains_where_torch_has_a_gpu_and_cpu_forces_the_cpu():
    torch = import_torch()
    from uavcas.ids.nets import CNN1D
    x, y = _data(seed=3)
    auto = TorchClassifier(network=CNN1D, epochs=2, n_threads=1).fit(x, y)
    assert auto.device_ == ("cuda" if torch.cuda.is_available() else "cpu")
    cpu = TorchClassifier(network=CNN1D, epochs=2, n_threads=1, device="cpu").fit(x, y)
    assert cpu.device_ == "cpu" and cpu.predict_proba(x[:5]).shape == (5, 3)
    with pytest.raises(ValueError, match="device 'tpu'"):
        TorchClassifier(network=CNN1D, device="tpu").fit(x, y)
    if not torch.cuda.is_available():
        with pytest.raises(ValueError, match="sees no CUDA GPU"):
            TorchClassifier(network=CNN1D, epochs=1, device="cuda").fit(x, y)
    assert make_model("lstm", device="cpu").get_params()["device"] == "cpu"
    assert "device" not in make_model("rf").get_params()


def test_clear_error_without_torch(monkeypatch):
    monkeypatch.setitem(sys.modules, "torch", None)  # import torch -> ImportError
    with pytest.raises(ImportError, match="uavcas\\[dl\\]"):
        import_torch()
    assert "torch==2.13.0" in DL_MISSING


def test_unknown_model_and_network():
    with pytest.raises(ValueError, match="unknown detector 'xgboost'; known: lr, sgd, rf"):
        make_model("xgboost")
    with pytest.raises(ValueError, match="network"):
        TorchClassifier().fit(*_data())
    with pytest.raises(ValueError, match="network"):
        TorchClassifier(network="transformer").fit(*_data())


@pytest.mark.parametrize("name", ALL)
def test_baseline_by_name_with_overrides(name):
    est = baseline(name, random_state=7)
    assert est.get_params()["random_state"] == 7
    assert baseline(name.upper()).get_params() == baseline(name).get_params()
    with pytest.raises(ValueError):
        baseline(name, no_such_parameter=1)


def test_baseline_paper_settings():
    assert baseline("rf").n_estimators == 100 and baseline("rf", n_estimators=10).n_estimators == 10
    assert baseline("mlp").get_params()["hidden_layer_sizes"] == (128, 64)
    assert baseline("mlp").max_iter == 50 and baseline("mlp").n_iter_no_change == 5


def _noisy(seed):
    rng = np.random.default_rng(seed)
    x = rng.normal(size=(300, 6))
    y = np.where(x[:, 0] + 0.8 * rng.normal(size=300) > 0, "DoS", "Benign")
    return x, y


def test_mlp_early_stops_on_the_given_validation_split():
    x, y = _noisy(0)
    xv, yv = _noisy(1)
    est = GroupedMLPClassifier(max_iter=40, n_iter_no_change=3, batch_size=32).fit(x, y, X_val=xv, y_val=yv)
    assert est.n_iter_ == len(est.validation_loss_) <= 40
    # the weights kept are those of the epoch with the lowest loss on the split we passed
    yi = np.searchsorted(est.classes_, yv)
    assert log_loss(yi, est.predict_proba(xv)) == pytest.approx(min(est.validation_loss_), rel=1e-9)
    # labels unrelated to X: the validation loss never improves for long, so it stops early
    noise = np.random.default_rng(2).permutation(yv)
    early = GroupedMLPClassifier(max_iter=40, n_iter_no_change=3, batch_size=32).fit(x, y, X_val=xv, y_val=noise)
    assert early.n_iter_ < est.n_iter_


def test_lightgbm_early_stops_on_the_given_validation_split():
    x, y = _noisy(3)
    xv, yv = _noisy(4)
    full = LightGBMClassifier(n_estimators=300, n_jobs=1).fit(x, y)
    stopped = LightGBMClassifier(n_estimators=300, n_jobs=1, early_stopping_rounds=5).fit(x, y, X_val=xv, y_val=yv)
    assert full.n_iter_ == 300 and stopped.n_iter_ < 300


@pytest.mark.parametrize("name", ALL)
def test_predict_before_fit_and_bad_input(name):
    from sklearn.exceptions import NotFittedError

    est = _model(name)
    with pytest.raises(NotFittedError):
        est.predict(np.zeros((2, 47)))
    x, y = _data(n=40)
    x[3, 5] = np.inf  # (NaN is a valid "missing" value for RF; inf is never)
    with pytest.raises(ValueError):
        _model(name).fit(x, y)
