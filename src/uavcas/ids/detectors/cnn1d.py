"""1D-CNN: a 1-D convolutional network (Hassler et al. 2024), a paper baseline; the network is
`uavcas.ids.nets.CNN1D`, trained by `uavcas.ids.torch_estimator.TorchClassifier`."""

from __future__ import annotations

from uavcas.ids.base import PATIENCE
from uavcas.ids.torch_estimator import TorchClassifier

from .registry import register
from .spec import DetectorSpec


def _factory():
    # deferred: `nets` imports torch (the optional `dl` extra) at module level; the registry loads without it
    from uavcas.ids.nets import CNN1D

    return TorchClassifier(network=CNN1D, epochs=50, patience=PATIENCE)


SPEC = register(DetectorSpec(name="cnn1d", display="1D-CNN", kind="deep", factory=_factory, order=60,
                             epoch_param="epochs", thread_param="n_threads", paper_baseline=True))
