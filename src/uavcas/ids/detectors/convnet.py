"""ConvNet: UAV-IDS-ConvNet, three convolution blocks (Al-Haija & Al Badawi 2022), a paper baseline; the network is
`uavcas.ids.nets.ConvNet`, trained by `uavcas.ids.torch_estimator.TorchClassifier`."""

from __future__ import annotations

from uavcas.ids.base import PATIENCE
from uavcas.ids.torch_estimator import TorchClassifier

from .registry import register
from .spec import DetectorSpec


def _factory():
    # deferred: `nets` imports torch (the optional `dl` extra) at module level; the registry loads without it
    from uavcas.ids.nets import ConvNet

    return TorchClassifier(network=ConvNet, epochs=50, patience=PATIENCE)


SPEC = register(DetectorSpec(name="convnet", display="ConvNet", kind="deep", factory=_factory, order=80,
                             epoch_param="epochs", thread_param="n_threads", paper_baseline=True))
