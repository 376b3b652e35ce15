"""Free space (Friis): the loss of an unobstructed path with isotropic antennas.

    PL = 20 log10(4 pi d f / c),   d = 3-D distance (floored at 1 m), f = carrier

(H. T. Friis, "A note on a simple transmission formula", Proc. IRE 34(5), 1946; the same law as
ITU-R P.525-4). Deterministic: `sigma_db` (default 0) adds shadowing if wanted.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.constants import c as SPEED_OF_LIGHT_M_S

from ..geometry import MIN_DISTANCE_M, LinkGeometry, PathLossResult
from .base import DEFAULT_FC_GHZ, PathLossOptions, PathLossSpec
from .registry import register


def free_space_loss_db(d_m, fc_ghz: float = DEFAULT_FC_GHZ) -> np.ndarray:
    """Friis: 20 log10(4 pi d f / c)."""
    d = np.maximum(np.asarray(d_m, dtype=float), MIN_DISTANCE_M)
    return 20.0 * np.log10(4.0 * np.pi * d * fc_ghz * 1e9 / SPEED_OF_LIGHT_M_S)


@dataclass(frozen=True)
class FreeSpace:
    """Friis free-space loss on the 3-D distance; `sigma_db` (default 0: deterministic)."""

    fc_ghz: float = DEFAULT_FC_GHZ
    sigma_db: float = 0.0
    name = "freespace"
    samples_los = False

    def loss_at_db(self, d3d_m) -> np.ndarray:
        return free_space_loss_db(d3d_m, self.fc_ghz)

    def loss_db(self, geom: LinkGeometry) -> np.ndarray:
        return self.loss_at_db(geom.d3d_m)

    def evaluate(self, geom: LinkGeometry, los_uniform: np.ndarray | None = None) -> PathLossResult:
        loss = self.loss_db(geom)
        return PathLossResult(loss, np.full(loss.shape, self.sigma_db), None)


register(PathLossSpec(
    name="freespace", model=FreeSpace,
    standard="Friis 1946 (= ITU-R P.525-4), on the 3-D distance",
    summary="free space (Friis), deterministic",
    build=lambda o: FreeSpace(fc_ghz=o.carrier_ghz),
))

__all__ = ["FreeSpace", "PathLossOptions", "free_space_loss_db"]
