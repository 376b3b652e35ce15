"""Context-joint: the context detector's ablation that learns the flow features and the context columns
in one model instead of two stages (`uavcas.ids.context`)."""

from __future__ import annotations

from uavcas.ids.context import ContextClassifier

from .registry import register
from .spec import DetectorSpec


def _factory():
    return ContextClassifier(inputs="both", residual=False)


SPEC = register(DetectorSpec(name="context-joint", display="Context-joint", kind="context", factory=_factory, order=120,
                             thread_param="n_jobs", tree=True))
