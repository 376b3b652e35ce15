"""LSTM: an LSTM over the feature vector as one time step (Hassler et al. 2024), a paper baseline; the network is
`uavcas.ids.nets.LSTMNet`, trained by `uavcas.ids.torch_estimator.TorchClassifier`."""

from __future__ import annotations

from uavcas.ids.base import PATIENCE
from uavcas.ids.torch_estimator import TorchClassifier

from .registry import register
from .spec import DetectorSpec


def _factory():
    # deferred: `nets` imports torch (the optional `dl` extra) at module level; the registry loads without it
    from uavcas.ids.nets import LSTMNet

    return TorchClassifier(network=LSTMNet, epochs=50, patience=PATIENCE)


SPEC = register(DetectorSpec(name="lstm", display="LSTM", kind="deep", factory=_factory, order=70,
                             epoch_param="epochs", thread_param="n_threads", paper_baseline=True))
