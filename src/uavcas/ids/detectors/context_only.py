"""Context-only: the context detector's ablation that learns from the context columns only
(`uavcas.ids.context`)."""

from __future__ import annotations

from uavcas.ids.context import ContextClassifier

from .registry import register
from .spec import DetectorSpec


def _factory():
    return ContextClassifier(inputs="context")


SPEC = register(DetectorSpec(name="context-only", display="Context-only", kind="context", factory=_factory, order=140,
                             thread_param="n_jobs", tree=True))
