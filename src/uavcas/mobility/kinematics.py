"""Speed, heading-change rate, vertical speed and altitude of sampled trajectories.

Used by calibration (real flights and simulated missions go through the *same* function, so
their distributions are comparable) and by the tests. Finite differences between consecutive
samples: segment quantities have T-1 values, heading-change rates T-2 (between segments).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class Kinematics:
    """Arrays are (T-1, ...) per segment unless stated; trailing dims follow the positions'
    (no UAV axis for (T, 3) input, one for (T, n, 3))."""

    t_mid_s: np.ndarray  # (T-1,) segment mid-times
    horizontal_speed_mps: np.ndarray  # |dx/dt, dy/dt|
    vertical_speed_mps: np.ndarray  # dz/dt (positive = climbing)
    heading_rad: np.ndarray  # atan2(dy, dx) of each segment (0 where the UAV does not move)
    heading_rate_radps: np.ndarray  # (T-2, ...) signed turn between segments / time, in (-pi, pi]/dt
    altitude_m: np.ndarray  # (T, ...) z at the samples


def kinematics(positions_m: np.ndarray, t_s: np.ndarray) -> Kinematics:
    x = np.asarray(positions_m, dtype=float)
    t = np.asarray(t_s, dtype=float)
    if x.ndim not in (2, 3) or x.shape[-1] != 3 or x.shape[0] != t.shape[0] or t.ndim != 1:
        raise ValueError(f"need positions (T, 3) or (T, n, 3) and t_s (T,); got {x.shape} and {t.shape}")
    if t.size < 2 or np.any(np.diff(t) <= 0):
        raise ValueError("t_s needs at least two strictly increasing samples")
    dt = np.diff(t).reshape((-1,) + (1,) * (x.ndim - 2))
    d = np.diff(x, axis=0)
    vx, vy, vz = d[..., 0] / dt, d[..., 1] / dt, d[..., 2] / dt
    # Heading change from the cross/dot product of consecutive ground vectors: wrap-free, and
    # exactly 0 when either segment is a hover (atan2(0, 0) = 0) instead of a spurious jump.
    cross = d[:-1, ..., 0] * d[1:, ..., 1] - d[:-1, ..., 1] * d[1:, ..., 0]
    dot = d[:-1, ..., 0] * d[1:, ..., 0] + d[:-1, ..., 1] * d[1:, ..., 1]
    t_mid = (t[:-1] + t[1:]) / 2.0
    dt_mid = np.diff(t_mid).reshape((-1,) + (1,) * (x.ndim - 2))
    return Kinematics(
        t_mid_s=t_mid,
        horizontal_speed_mps=np.hypot(vx, vy),
        vertical_speed_mps=vz,
        heading_rad=np.arctan2(vy, vx),
        heading_rate_radps=np.arctan2(cross, dot) / dt_mid,
        altitude_m=x[..., 2].copy(),
    )
