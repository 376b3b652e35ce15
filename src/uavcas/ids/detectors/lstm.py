"""LSTM: an LSTM over the feature vector as one time step (Hassler et al. 2024), a paper baseline; the network is
`uavcas.ids.nets.LSTMNet`, trained by `uavcas.ids.torch_estimator.TorchClassifier`."""

from __future__ import annotations

from .registry import register
from .spec import DetectorSpec


def _factory():
    # torch (the optional `dl` extra) is imported when the detector is built, never with the registry
    from uavcas.ids.base import PATIENCE
    from uavcas.ids.nets import LSTMNet
    from uavcas.ids.torch_estimator import TorchClassifier

    return TorchClassifier(network=LSTMNet, epochs=50, patience=PATIENCE)


SPEC = register(DetectorSpec(name="lstm", display="LSTM", kind="deep", factory=_factory, order=70,
                             epoch_param="epochs", thread_param="n_threads", paper_baseline=True))
