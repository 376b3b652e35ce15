"""Context-flow: the context detector's ablation that learns from the flow features only (what the ten
baselines see; `uavcas.ids.context`)."""

from __future__ import annotations

from uavcas.ids.context import ContextClassifier

from .registry import register
from .spec import DetectorSpec


def _factory():
    return ContextClassifier(inputs="flow")


SPEC = register(DetectorSpec(name="context-flow", display="Context-flow", kind="context", factory=_factory, order=130,
                             thread_param="n_jobs", tree=True))
