"""LR: logistic regression, a paper baseline (Hassler et al. 2024)."""

from __future__ import annotations

from sklearn.linear_model import LogisticRegression

from .registry import register
from .spec import DetectorSpec


def _factory():
    return LogisticRegression(max_iter=1000, random_state=0)


SPEC = register(DetectorSpec(name="lr", display="LR", kind="classical", factory=_factory, order=10,
                             paper_baseline=True))
