"""Context-only: the context detector's ablation that learns from the context columns only
(`uavcas.ids.context`)."""

from __future__ import annotations

from .registry import register
from .spec import DetectorSpec


def _factory():
    # LightGBM and scikit-learn are imported when the detector is built, not with the registry (the CLI reads it)
    from uavcas.ids.context import ContextClassifier

    return ContextClassifier(inputs="context")


SPEC = register(DetectorSpec(name="context-only", display="Context-only", kind="context", factory=_factory, order=140,
                             thread_param="n_jobs", tree=True))
