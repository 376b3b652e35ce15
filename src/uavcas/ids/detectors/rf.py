"""RF: a random forest of 100 trees, a paper baseline (Hassler et al. 2024)."""

from __future__ import annotations

from sklearn.ensemble import RandomForestClassifier

from .registry import register
from .spec import DetectorSpec


def _factory():
    return RandomForestClassifier(n_estimators=100, random_state=0)


SPEC = register(DetectorSpec(name="rf", display="RF", kind="classical", factory=_factory, order=30,
                             thread_param="n_jobs", tree=True, paper_baseline=True))
