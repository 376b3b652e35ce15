"""ConvNet: UAV-IDS-ConvNet, three convolution blocks (Al-Haija & Al Badawi 2022), a paper baseline; the network is
`uavcas.ids.nets.ConvNet`, trained by `uavcas.ids.torch_estimator.TorchClassifier`."""

from __future__ import annotations

from .registry import register
from .spec import DetectorSpec


def _factory():
    # torch (the optional `dl` extra) is imported when the detector is built, never with the registry
    from uavcas.ids.base import PATIENCE
    from uavcas.ids.nets import ConvNet
    from uavcas.ids.torch_estimator import TorchClassifier

    return TorchClassifier(network=ConvNet, epochs=50, patience=PATIENCE)


SPEC = register(DetectorSpec(name="convnet", display="ConvNet", kind="deep", factory=_factory, order=80,
                             epoch_param="epochs", thread_param="n_threads", paper_baseline=True))
