"""Estimating Gauss–Markov parameters from sampled velocities (calibration layer 2).

The estimator is the model's own AR(1) form, so a fitted `GaussMarkovParams` drives exactly the
generator it was fitted for (`GaussMarkovMission`):
    v_k - m_s = a (v_{k-1} - m_s) + e_k,   Var e = (1 - a^2) sigma^2
fitted per axis by least squares pooled over series (flights / UAVs) with a separate mean m_s
per series (the "within" estimator): each flight has its own preferred heading, so a single
pooled intercept would read heading differences as memory. sigma^2 = Var(e) / (1 - a^2).
The returned `step_s` is the sampling step; `alpha` is per that step (see the time-scaling rule
in `params.GaussMarkovParams`).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Sequence

import numpy as np

from uavcas.mobility.params import GaussMarkovParams


@dataclass(frozen=True)
class GaussMarkovFit:
    step_s: float
    alpha_axes: np.ndarray  # (3,) per-axis AR(1) coefficient at step_s
    sigma2_axes_mps2: np.ndarray  # (3,) per-axis stationary variance
    mean_velocity_mps: np.ndarray  # (3,) mean over all samples (z: the descent tendency)
    mean_horizontal_speed_mps: float  # E|v_xy| over all samples: what the generator honours
    alpha: float  # pooled over x and y (the horizontal walk the speed law depends on)
    sigma2_mps2: float  # pooled over x and y
    n_samples: int

    def to_params(self, **overrides) -> GaussMarkovParams:
        """Parameters for `GaussMarkovMission` (vertical sigma fitted separately)."""
        values = dict(
            alpha=float(np.clip(self.alpha, 0.0, 0.999999)),
            mean_speed_mps=self.mean_horizontal_speed_mps,
            sigma2_mps2=self.sigma2_mps2,
            step_s=self.step_s,
            mean_vz_mps=float(self.mean_velocity_mps[2]),
            sigma2_z_mps2=float(self.sigma2_axes_mps2[2]),
        )
        values.update(overrides)
        return GaussMarkovParams(**values)


def _as_series(velocities_mps: np.ndarray | Sequence[np.ndarray]) -> list[np.ndarray]:
    """Normalise input to a list of (T_s, 3) series."""
    if isinstance(velocities_mps, np.ndarray):
        v = velocities_mps
        if v.ndim == 2:
            return [v]
        if v.ndim == 3:
            return [v[:, i, :] for i in range(v.shape[1])]
        raise ValueError(f"velocities must be (T, 3), (T, n, 3) or a list of (T, 3); got {v.shape}")
    out = []
    for s in velocities_mps:
        out.extend(_as_series(np.asarray(s, dtype=float)))
    return out


def fit_gauss_markov(velocities_mps: np.ndarray | Sequence[np.ndarray], step_s: float) -> GaussMarkovFit:
    """Estimate (alpha, mean velocity, sigma) from velocity series sampled every `step_s`."""
    if step_s <= 0:
        raise ValueError("step_s must be > 0")
    series = [np.asarray(s, dtype=float) for s in _as_series(velocities_mps)]
    series = [s for s in series if s.shape[0] >= 3]
    if not series or any(s.shape[-1] != 3 for s in series):
        raise ValueError("need at least one velocity series of >= 3 samples with 3 axes")
    sxx = np.zeros(3)
    sxy = np.zeros(3)
    pairs = []
    for s in series:
        x = s[:-1] - s[:-1].mean(axis=0)
        y = s[1:] - s[1:].mean(axis=0)
        sxx += (x * x).sum(axis=0)
        sxy += (x * y).sum(axis=0)
        pairs.append((x, y))
    alpha_axes = np.divide(sxy, sxx, out=np.zeros(3), where=sxx > 0)
    alpha_h = float(sxy[:2].sum() / sxx[:2].sum()) if sxx[:2].sum() > 0 else 0.0
    # Residual variance with the per-series means and the slope as fitted degrees of freedom.
    n_pairs = sum(x.shape[0] for x, _ in pairs)
    dof = max(n_pairs - len(pairs) - 1, 1)
    res_axes = sum(((y - alpha_axes * x) ** 2).sum(axis=0) for x, y in pairs) / dof
    res_h = sum(((y[:, :2] - alpha_h * x[:, :2]) ** 2).sum() for x, y in pairs) / (2 * dof)
    sigma2_axes = res_axes / np.maximum(1.0 - alpha_axes**2, 1e-12)
    sigma2_h = float(res_h / max(1.0 - alpha_h**2, 1e-12))
    allv = np.concatenate(series, axis=0)
    return GaussMarkovFit(
        step_s=float(step_s),
        alpha_axes=alpha_axes,
        sigma2_axes_mps2=sigma2_axes,
        mean_velocity_mps=allv.mean(axis=0),
        mean_horizontal_speed_mps=float(np.hypot(allv[:, 0], allv[:, 1]).mean()),
        alpha=alpha_h,
        sigma2_mps2=sigma2_h,
        n_samples=int(allv.shape[0]),
    )


def resample_uniform(t_s: np.ndarray, positions_m: np.ndarray, step_s: float) -> tuple[np.ndarray, np.ndarray]:
    """Linearly resample an irregular track (T, 3) or (T, n, 3) onto t0, t0+step, ... <= t_end.

    Real logs (e.g. AFAR at ~30 Hz with jitter) must be put on one step before fitting, since
    alpha is defined per step."""
    t = np.asarray(t_s, dtype=float)
    x = np.asarray(positions_m, dtype=float)
    if t.ndim != 1 or x.shape[0] != t.size or np.any(np.diff(t) <= 0):
        raise ValueError("need strictly increasing t_s (T,) and positions with T rows")
    grid = t[0] + step_s * np.arange(int(np.floor((t[-1] - t[0]) / step_s + 1e-9)) + 1)
    flat = x.reshape(t.size, -1)
    out = np.stack([np.interp(grid, t, flat[:, j]) for j in range(flat.shape[1])], axis=1)
    return grid, out.reshape((grid.size,) + x.shape[1:])


def velocities_from_positions(positions_m: np.ndarray, step_s: float) -> np.ndarray:
    """Forward-difference velocities (T-1, ..., 3) of a uniformly sampled track."""
    return np.diff(np.asarray(positions_m, dtype=float), axis=0) / step_s


@dataclass(frozen=True)
class Legs:
    """Straight legs of a flown track (`split_legs`), one entry per leg."""

    length_m: np.ndarray
    duration_s: np.ndarray
    peak_speed_mps: np.ndarray  # 90th percentile of the leg's sampled ground speeds
    altitude_m: np.ndarray  # median altitude flown on the leg


def _douglas_peucker(p: np.ndarray, tol_m: float) -> np.ndarray:
    """Indices of the vertices kept by Douglas-Peucker simplification of a 2-D polyline."""
    keep = np.zeros(len(p), dtype=bool)
    keep[[0, -1]] = True
    stack = [(0, len(p) - 1)]
    while stack:
        a, b = stack.pop()
        if b <= a + 1:
            continue
        seg = p[b] - p[a]
        rel = p[a + 1 : b] - p[a]
        norm = float(np.hypot(*seg))
        d = np.abs(seg[0] * rel[:, 1] - seg[1] * rel[:, 0]) / norm if norm > 0 else np.hypot(rel[:, 0], rel[:, 1])
        k = int(np.argmax(d))
        if d[k] > tol_m:
            keep[a + 1 + k] = True
            stack += [(a, a + 1 + k), (a + 1 + k, b)]
    return np.flatnonzero(keep)


def split_legs(positions_m: np.ndarray, t_s: np.ndarray, tol_m: float = 4.0) -> Legs:
    """Cut a uniformly sampled track (T, 3) into straight legs: the vertices of its Douglas-Peucker
    simplification with tolerance `tol_m` (GPS noise and the turns' rounding stay inside)."""
    x = np.asarray(positions_m, dtype=float)
    t = np.asarray(t_s, dtype=float)
    idx = _douglas_peucker(x[:, :2], tol_m)
    speed = np.hypot(*np.diff(x[:, :2], axis=0).T) / np.diff(t)
    a, b = idx[:-1], idx[1:]
    return Legs(
        length_m=np.hypot(*(x[b, :2] - x[a, :2]).T),
        duration_s=t[b] - t[a],
        peak_speed_mps=np.array([np.percentile(speed[i:j], 90) for i, j in zip(a, b)]),
        altitude_m=np.array([np.median(x[i : j + 1, 2]) for i, j in zip(a, b)]),
    )
