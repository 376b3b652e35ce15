"""Every detector's estimator class passes scikit-learn's `check_estimator` suite, and every
deep detector's network passes the checks that exercise a network.

The checks are about an estimator *class* (its API contract: parameters, cloning, input
validation, fitted state), so, as scikit-learn's own suite does (one instance per class:
sklearn/utils/_test_common/instance_generator.py, `_tested_estimators`), the whole suite runs
once per class: LogisticRegression, SGDClassifier, RandomForestClassifier, GroupedMLPClassifier,
LightGBMClassifier, TorchClassifier (with the first deep detector's network) and
ContextClassifier. The five deep detectors are one class, TorchClassifier, differing only in
their network: each network gets the checks whose outcome depends on the network (it learns the
toy problem, takes one feature, one sample, a 1-D input is refused, fitting twice gives the same
model, predictions do not depend on the batch), not the 55 API checks again. This keeps the
checks' cost to one network's instead of five (issue 40: the full suite in 15 minutes).

The checking instances keep the paper's architectures and optimisers but use small batches and
few epochs, so the networks learn the checks' 300-row toy problems (accuracy > 0.83 is one
check) in seconds, as scikit-learn's own suite sets fast parameters for its estimators.
"""

from __future__ import annotations

import importlib.util

import pytest
from sklearn.utils.estimator_checks import (
    check_classifiers_train,
    check_fit2d_1feature,
    check_fit2d_1sample,
    check_fit2d_predict1d,
    check_fit_idempotent,
    check_methods_subset_invariance,
    parametrize_with_checks,
)

from uavcas.ids import baseline, detectors

HAS_TORCH = importlib.util.find_spec("torch") is not None
DEEP = tuple(s.name for s in detectors() if s.needs_torch)
FAST = {"mlp": {"batch_size": 16, "max_iter": 20},
        **{d: {"batch_size": 16, "epochs": 20, "n_threads": 1} for d in DEEP}}
# every registered detector but the context ablation (one class for the four context variants:
# they differ in the columns they select by name, and an array without names is taken whole)
NAMES = tuple(s.name for s in detectors()
              if (HAS_TORCH or not s.needs_torch) and (not s.uses_context or s.name == "context"))
# one name per estimator class for the whole suite (the first deep detector stands for the
# TorchClassifier class); every other deep detector's network gets NETWORK_CHECKS
FULL = tuple(n for n in NAMES if n not in DEEP or n == DEEP[0])
NETWORKS = tuple(n for n in NAMES if n in DEEP and n != DEEP[0])
ESTIMATORS = [baseline(n, **FAST.get(n, {})) for n in FULL]
NETWORK_CHECKS = (check_classifiers_train, check_fit2d_1feature, check_fit2d_1sample, check_fit2d_predict1d,
                  check_fit_idempotent, check_methods_subset_invariance)

# The same reason scikit-learn gives for RandomForestClassifier and SGDClassifier in its own
# suite (sklearn/utils/_test_common/instance_generator.py): bootstrap samples and stochastic
# updates make fitting with weight 2 differ from repeating a row, so the exact-equality check
# cannot apply to these randomised estimators.
_WEIGHTS = "sample_weight is not equivalent to removing/repeating samples (randomised fit)"
XFAIL = {
    "RandomForestClassifier": {"check_sample_weight_equivalence_on_dense_data": _WEIGHTS,
                               "check_sample_weight_equivalence_on_sparse_data": _WEIGHTS},
    "SGDClassifier": {"check_sample_weight_equivalence_on_dense_data": _WEIGHTS,
                      "check_sample_weight_equivalence_on_sparse_data": _WEIGHTS},
}


def _expected_failures(est) -> dict[str, str]:
    return XFAIL.get(type(est).__name__, {})


@parametrize_with_checks(ESTIMATORS, expected_failed_checks=_expected_failures)
def test_sklearn_check_estimator(estimator, check):
    check(estimator)


def test_one_instance_per_estimator_class_gets_the_whole_suite():
    classes = [type(e).__name__ for e in ESTIMATORS]
    assert len(classes) == len(set(classes))  # no class checked twice
    every = {type(baseline(n, **FAST.get(n, {}))).__name__ for n in NAMES}
    assert set(classes) == every  # and none left out


@pytest.mark.parametrize("check", NETWORK_CHECKS, ids=lambda c: c.__name__)
@pytest.mark.parametrize("name", NETWORKS)
def test_every_deep_detectors_network_passes_the_network_checks(name, check):
    est = baseline(name, **FAST.get(name, {}))
    check(type(est).__name__, est)


@pytest.mark.skipif(HAS_TORCH, reason="PyTorch installed: the deep baselines are checked above")
def test_deep_baselines_need_torch():
    pytest.skip("PyTorch not installed (pip install '.[dl]'): the five deep baselines are not checked")
