"""Replay of a recorded trajectory (calibration layer 3 feeds real flights through the twin).

Positions are linearly interpolated between samples and held at the first/last sample outside
the recording. Time 0 of the mission is the first sample (times are re-based), so a trace obeys
the same `positions(t_s)` contract as the synthetic missions.
"""

from __future__ import annotations

import numpy as np

from uavcas.mobility.area import Area
from uavcas.mobility.base import MissionBase


class TraceMission(MissionBase):
    kind = "trace"

    def __init__(self, t_s: np.ndarray, positions_m: np.ndarray, area: Area | None = None):
        """t_s (T,) strictly increasing seconds; positions_m (T, 3) for one UAV or (T, n, 3).

        With `area`, positions are clipped into it (documented: real flights below 30 m, e.g. AFAR
        at 20-48 m, are lifted to the band); with area=None they are replayed as recorded.
        """
        t = np.asarray(t_s, dtype=float)
        x = np.asarray(positions_m, dtype=float)
        if x.ndim == 2:
            x = x[:, None, :]
        if t.ndim != 1 or t.size < 1 or x.ndim != 3 or x.shape[0] != t.size or x.shape[2] != 3:
            raise ValueError(f"trace needs t_s (T,) and positions (T, 3) or (T, n, 3); got {t.shape} and "
                             f"{np.shape(positions_m)}")
        if not (np.all(np.isfinite(t)) and np.all(np.isfinite(x))):
            raise ValueError("trace times and positions must be finite")
        if np.any(np.diff(t) <= 0):
            raise ValueError("trace times must be strictly increasing")
        self.t0_s = float(t[0])
        self.t_s = t - t[0]
        self.area = area if area is not None else Area()
        self.clipped = area is not None  # False: replayed as recorded, `area` is nominal only
        self.track_m = area.clip(x) if area is not None else x
        self.n_uav = x.shape[1]

    @property
    def duration_s(self) -> float:
        return float(self.t_s[-1])

    def _positions(self, t: np.ndarray) -> np.ndarray:
        if self.t_s.size == 1:
            return np.broadcast_to(self.track_m[0], (t.size,) + self.track_m.shape[1:]).copy()
        tq = np.clip(t, 0.0, self.t_s[-1])
        k = np.clip(np.searchsorted(self.t_s, tq, side="right") - 1, 0, self.t_s.size - 2)
        frac = ((tq - self.t_s[k]) / (self.t_s[k + 1] - self.t_s[k]))[:, None, None]
        return (1.0 - frac) * self.track_m[k] + frac * self.track_m[k + 1]
