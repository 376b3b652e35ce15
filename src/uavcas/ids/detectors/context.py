"""Context: the context-aware detector: LightGBM on the flow features, then context trees boosted from the
flow model's scores on the `ctx_*` columns (two stages; `uavcas.ids.context`)."""

from __future__ import annotations

from uavcas.ids.context import ContextClassifier

from .registry import register
from .spec import DetectorSpec


def _factory():
    return ContextClassifier(inputs="both")


SPEC = register(DetectorSpec(name="context", display="Context", kind="context", factory=_factory, order=110,
                             thread_param="n_jobs", tree=True))
