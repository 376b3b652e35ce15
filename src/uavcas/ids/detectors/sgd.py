"""SGD: a linear model trained by stochastic gradient descent, a paper baseline (Hassler et al. 2024)."""

from __future__ import annotations

from sklearn.linear_model import SGDClassifier

from .registry import register
from .spec import DetectorSpec


def _factory():
    # log loss so that predict_proba exists (AUROC and PR-AUC need scores)
    return SGDClassifier(loss="log_loss", max_iter=1000, tol=1e-4, random_state=0)


SPEC = register(DetectorSpec(name="sgd", display="SGD", kind="classical", factory=_factory, order=20,
                             paper_baseline=True))
