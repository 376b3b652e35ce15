"""Constant-speed motion along a 2-D polyline, evaluated by arc length (vectorised over time)."""

from __future__ import annotations

import numpy as np


class Polyline:
    def __init__(self, vertices_m: np.ndarray):
        v = np.asarray(vertices_m, dtype=float)
        if v.ndim != 2 or v.shape[0] < 2:
            raise ValueError("a polyline needs at least two vertices (V, d)")
        self.vertices_m = v
        seg = np.linalg.norm(np.diff(v, axis=0), axis=1)
        self.cum_m = np.concatenate([[0.0], np.cumsum(seg)])
        self.length_m = float(self.cum_m[-1])

    def at(self, s_m: np.ndarray) -> np.ndarray:
        """Points at arc lengths s (clipped to [0, length]); shape s.shape + (d,)."""
        s = np.clip(np.asarray(s_m, dtype=float), 0.0, self.length_m)
        # Piecewise-linear in s: interpolate each coordinate against the cumulative length.
        return np.stack([np.interp(s, self.cum_m, self.vertices_m[:, k]) for k in range(self.vertices_m.shape[1])], axis=-1)
