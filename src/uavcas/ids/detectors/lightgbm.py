"""LightGBM: gradient-boosted trees, early-stopped on the protocol's grouped validation split, a
paper baseline (Silva et al. 2023; `uavcas.ids.classical.LightGBMClassifier`)."""

from __future__ import annotations

from uavcas.ids.classical import LightGBMClassifier

from .registry import register
from .spec import DetectorSpec


def _factory():
    return LightGBMClassifier(n_estimators=200, learning_rate=0.1, num_leaves=31)


SPEC = register(DetectorSpec(name="lightgbm", display="LightGBM", kind="classical", factory=_factory, order=50,
                             thread_param="n_jobs", tree=True, paper_baseline=True))
