"""The mission protocol, time handling shared by every mission, and seeded per-UAV placement.

Every mission answers `positions(t_s)`: (n_uav, 3) metres for a scalar time, (len(t), n_uav, 3)
for a 1-D array of times, evaluated in closed form or from a cached simulation, so the answer
for a time never depends on which other times were asked before (plans must be bit-for-bit
reproducible). Randomness comes only from `uavcas.seeding` streams of an integer seed (never
Python's hash(), which is salted per process).
"""

from __future__ import annotations

from typing import Protocol, runtime_checkable

import numpy as np

from uavcas.mobility.area import Area


@runtime_checkable
class Mission(Protocol):
    n_uav: int
    area: Area

    def positions(self, t_s: float | np.ndarray) -> np.ndarray:
        """(n_uav, 3) for a scalar time, (len(t), n_uav, 3) for a 1-D array of times (metres)."""
        ...


class MissionBase:
    """Validates times and restores the scalar/array shape contract; subclasses implement
    `_positions(t: (T,) float array) -> (T, n_uav, 3)`."""

    n_uav: int
    area: Area

    def positions(self, t_s: float | np.ndarray) -> np.ndarray:
        t = np.asarray(t_s, dtype=float)
        if t.ndim > 1:
            raise ValueError(f"t_s must be a scalar or a 1-D array, got shape {t.shape}")
        if not np.all(np.isfinite(t)) or np.any(t < 0):
            raise ValueError("t_s must be finite and >= 0 (seconds from the start of the mission)")
        out = self._positions(np.atleast_1d(t))
        return out[0] if t.ndim == 0 else out

    def _positions(self, t: np.ndarray) -> np.ndarray:  # pragma: no cover - abstract
        raise NotImplementedError


def seeded_anchors(
    rng: np.random.Generator,
    n: int,
    lo: np.ndarray,
    hi: np.ndarray,
    min_separation_m: float,
    tries_per_point: int = 64,
) -> np.ndarray:
    """n points uniform in the box [lo, hi] (2-D or 3-D), at least `min_separation_m` apart
    in the horizontal plane where feasible.

    Dart throwing: each point gets `tries_per_point` candidates; if none is far enough from the
    points already placed (a crowded box), the candidate farthest from them is kept, so the call
    always returns n points, deterministically for a given generator state.
    """
    lo = np.asarray(lo, dtype=float)
    hi = np.asarray(hi, dtype=float)
    dim = lo.shape[0]
    if min_separation_m <= 0:
        return lo + rng.random((n, dim)) * (hi - lo)
    # O(n^2) dart throwing: fine for swarms (plans use <= 100 UAVs); pass 0 for thousands.
    out = np.empty((n, dim))
    for i in range(n):
        cand = lo + rng.random((tries_per_point, dim)) * (hi - lo)
        if i == 0:
            out[i] = cand[0]
            continue
        d = np.linalg.norm(cand[:, None, :2] - out[None, :i, :2], axis=-1).min(axis=1)
        ok = np.flatnonzero(d >= min_separation_m)
        out[i] = cand[ok[0]] if ok.size else cand[int(np.argmax(d))]
    return out


def anchor_box(area: Area, half_extent_m: float, margin_m: float) -> tuple[np.ndarray, np.ndarray]:
    """Horizontal box where a footprint of half-size `half_extent_m` centred on the anchor stays
    `margin_m` inside the area; collapses to the area centre if the footprint cannot fit."""
    size = np.array([area.x_max_m, area.y_max_m])
    pad = np.minimum(half_extent_m + margin_m, size / 2.0)
    return pad, size - pad
