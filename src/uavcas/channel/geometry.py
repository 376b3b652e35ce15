"""Per-link geometry and the common result type of every path-loss model.

Each link has a *ground end* and an *aerial end*, because every model we implement was defined
for a ground station talking to an elevated terminal (3GPP: BS and aerial UE; the log-distance
fit: AERPAW tower and UAV; two-ray: two antennas over flat ground):

* UAV-BS: the BS is the ground end (antenna at the BS position's z, the mast height), the UAV
  the aerial end.
* UAV-UAV (``air_to_air``): the lower UAV plays the ground end, the higher one the aerial end;
  each model's docstring says how it treats such links.
* BS-BS (normally a wired backhaul, evaluated only because the plan asks for every pair): the
  lower node is the ground end, like UAV-UAV, but the link is not marked air-to-air.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

MIN_DISTANCE_M = 1.0  # models are not defined inside their d0 = 1 m reference distance


@dataclass(frozen=True, eq=False)
class LinkGeometry:
    """Arrays of shape (k,): one entry per link."""

    d3d_m: np.ndarray  # straight-line distance between the antennas
    d2d_m: np.ndarray  # horizontal distance
    h_ground_m: np.ndarray  # antenna height of the ground end (BS, or the lower UAV)
    h_air_m: np.ndarray  # antenna height of the aerial end (UAV altitude)
    air_to_air: np.ndarray  # bool: both ends are UAVs

    @classmethod
    def from_positions(
        cls, pos_a_m: np.ndarray, pos_b_m: np.ndarray, a_is_bs: np.ndarray, b_is_bs: np.ndarray
    ) -> LinkGeometry:
        a = np.asarray(pos_a_m, dtype=float).reshape(-1, 3)
        b = np.asarray(pos_b_m, dtype=float).reshape(-1, 3)
        a_bs = np.broadcast_to(np.asarray(a_is_bs, dtype=bool), len(a))
        b_bs = np.broadcast_to(np.asarray(b_is_bs, dtype=bool), len(b))
        za, zb = a[:, 2], b[:, 2]
        # Exactly one BS: it is the ground end. Otherwise the lower node is.
        a_ground = np.where(a_bs != b_bs, a_bs, za <= zb)
        return cls(
            d3d_m=np.linalg.norm(a - b, axis=1),
            d2d_m=np.linalg.norm(a[:, :2] - b[:, :2], axis=1),
            h_ground_m=np.where(a_ground, za, zb),
            h_air_m=np.where(a_ground, zb, za),
            air_to_air=~a_bs & ~b_bs,
        )

    @classmethod
    def ground_to_air(
        cls, d2d_m: np.ndarray, h_air_m: np.ndarray, h_ground_m: float | np.ndarray = 25.0
    ) -> LinkGeometry:
        """Geometry of BS-UAV links from horizontal distance and heights (for tests and plots)."""
        d2d, h_air, h_g = np.broadcast_arrays(
            np.asarray(d2d_m, dtype=float),
            np.asarray(h_air_m, dtype=float),
            np.asarray(h_ground_m, dtype=float),
        )
        return cls(
            d3d_m=np.hypot(d2d, h_air - h_g),
            d2d_m=d2d,
            h_ground_m=h_g,
            h_air_m=h_air,
            air_to_air=np.zeros(d2d.shape, dtype=bool),
        )

    def __len__(self) -> int:
        return len(self.d3d_m)


@dataclass(frozen=True, eq=False)
class PathLossResult:
    """Median path loss (no shadowing), the shadowing std to apply, and the LOS state if any."""

    loss_db: np.ndarray
    sigma_db: np.ndarray
    los: np.ndarray | None  # bool per link for models with a LOS state (3GPP), else None
