"""The flight volume every mission is bounded to.

The paper places UAVs in a 1000 x 1000 m square at 30-110 m above ground (BSs sit on the ground,
outside this volume). The x/y origin is the square's corner so positions are always >= 0, which
keeps plan JSON readable and makes reflection arithmetic simple.
"""

from __future__ import annotations

import numpy as np
from pydantic import BaseModel, ConfigDict, Field, model_validator


class Area(BaseModel):
    """Axis-aligned box [0, x_max_m] x [0, y_max_m] x [z_min_m, z_max_m], metres."""

    model_config = ConfigDict(frozen=True, extra="forbid")

    x_max_m: float = Field(1000.0, gt=0)
    y_max_m: float = Field(1000.0, gt=0)
    z_min_m: float = Field(30.0, ge=0)
    z_max_m: float = Field(110.0, gt=0)

    @model_validator(mode="after")
    def _check_band(self) -> "Area":
        if self.z_max_m <= self.z_min_m:
            raise ValueError(f"altitude band is empty: z_min_m={self.z_min_m} >= z_max_m={self.z_max_m}")
        return self

    @property
    def lo_m(self) -> np.ndarray:
        """Lower corner (3,)."""
        return np.array([0.0, 0.0, self.z_min_m])

    @property
    def hi_m(self) -> np.ndarray:
        """Upper corner (3,)."""
        return np.array([self.x_max_m, self.y_max_m, self.z_max_m])

    def as_tuple(self) -> tuple[float, float, float, float]:
        """(x_max, y_max, z_min, z_max): the form `twin.Plan.area_m` stores."""
        return (self.x_max_m, self.y_max_m, self.z_min_m, self.z_max_m)

    def clamp_altitude(self, altitude_m: float) -> float:
        """A fitted altitude outside the band is clamped into it (paper: 25.96 m -> 30 m)."""
        return float(min(max(altitude_m, self.z_min_m), self.z_max_m))

    def contains(self, points_m: np.ndarray, tol_m: float = 1e-9) -> bool:
        """True when every point (..., 3) lies inside the box (with a float tolerance)."""
        p = np.asarray(points_m, dtype=float)
        return bool(np.all(p >= self.lo_m - tol_m) and np.all(p <= self.hi_m + tol_m))

    def clip(self, points_m: np.ndarray) -> np.ndarray:
        """Points (..., 3) clipped into the box."""
        return np.clip(np.asarray(points_m, dtype=float), self.lo_m, self.hi_m)


def reflect_into(x: np.ndarray, lo: np.ndarray, hi: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Fold coordinates back into [lo, hi] by mirror reflection on the faces.

    Works for any overshoot (even several box widths, e.g. a huge step), by folding on a period
    of 2 * width. Returns (folded x, flipped) where `flipped` is True on the components that went
    through an odd number of reflections, i.e. whose direction of motion must be negated.
    """
    width = hi - lo
    u = (x - lo) / width  # in units of the box width
    k = np.floor(u)
    frac = u - k
    odd = (k.astype(np.int64) % 2) == 1
    folded = np.where(odd, 1.0 - frac, frac)
    return lo + folded * width, odd
