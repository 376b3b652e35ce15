"""Context-flow: the context detector's ablation that learns from the flow features only (what the ten
baselines see; `uavcas.ids.context`)."""

from __future__ import annotations

from .registry import register
from .spec import DetectorSpec


def _factory():
    # LightGBM and scikit-learn are imported when the detector is built, not with the registry (the CLI reads it)
    from uavcas.ids.context import ContextClassifier

    return ContextClassifier(inputs="flow")


SPEC = register(DetectorSpec(name="context-flow", display="Context-flow", kind="context", factory=_factory, order=130,
                             thread_param="n_jobs", tree=True))
