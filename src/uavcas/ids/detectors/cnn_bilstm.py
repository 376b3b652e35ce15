"""CNN-BiLSTM: a convolution followed by a bidirectional LSTM (Sinha & Manollas 2020), a paper baseline; the network is
`uavcas.ids.nets.CNNBiLSTM`, trained by `uavcas.ids.torch_estimator.TorchClassifier`."""

from __future__ import annotations

from uavcas.ids.base import PATIENCE
from uavcas.ids.torch_estimator import TorchClassifier

from .registry import register
from .spec import DetectorSpec


def _factory():
    # deferred: `nets` imports torch (the optional `dl` extra) at module level; the registry loads without it
    from uavcas.ids.nets import CNNBiLSTM

    return TorchClassifier(network=CNNBiLSTM, epochs=50, patience=PATIENCE)


SPEC = register(DetectorSpec(name="cnn_bilstm", display="CNN-BiLSTM", kind="deep", factory=_factory, order=100,
                             epoch_param="epochs", thread_param="n_threads", paper_baseline=True))
