"""1D-CNN: a 1-D convolutional network (Hassler et al. 2024), a paper baseline; the network is
`uavcas.ids.nets.CNN1D`, trained by `uavcas.ids.torch_estimator.TorchClassifier`."""

from __future__ import annotations

from .registry import register
from .spec import DetectorSpec


def _factory():
    # torch (the optional `dl` extra) is imported when the detector is built, never with the registry
    from uavcas.ids.base import PATIENCE
    from uavcas.ids.nets import CNN1D
    from uavcas.ids.torch_estimator import TorchClassifier

    return TorchClassifier(network=CNN1D, epochs=50, patience=PATIENCE)


SPEC = register(DetectorSpec(name="cnn1d", display="1D-CNN", kind="deep", factory=_factory, order=60,
                             epoch_param="epochs", thread_param="n_threads", paper_baseline=True))
