"""MLP: two hidden layers (128-64), early-stopped on the protocol's grouped validation split, a
paper baseline (Hassler et al. 2024; `uavcas.ids.classical.GroupedMLPClassifier`)."""

from __future__ import annotations

from uavcas.ids.base import PATIENCE
from uavcas.ids.classical import GroupedMLPClassifier

from .registry import register
from .spec import DetectorSpec


def _factory():
    return GroupedMLPClassifier(max_iter=50, n_iter_no_change=PATIENCE)


SPEC = register(DetectorSpec(name="mlp", display="MLP", kind="classical", factory=_factory, order=40,
                             epoch_param="max_iter", paper_baseline=True))
