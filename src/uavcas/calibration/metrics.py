"""Error metrics and bounded divergences used by every layer (one definition, one place).

Errors (dB): e = predicted - measured. rmse = sqrt(mean e^2); mae = mean |e|; median_ae =
median |e|; bias = mean e (positive: the model predicts more loss / more power than measured);
r = Pearson correlation of predicted and measured (scipy.stats.pearsonr).

Divergences on shared histograms (`uavcas.stats.divergence`): Hellinger
H = ||sqrt p - sqrt q||_2 / sqrt 2 in [0, 1]; Jensen-Shannon *divergence* with base-2 logs in
[0, 1] (the square of scipy's JS distance). Spatial KL(real || sim) in bits over (x, y)
occupancy maps on a shared grid, smoothed as Lee's skew divergence: KL(p || (1 - lam) q + lam p)
with lam = `KL_SKEW` = 0.01. A simulated map with an empty cell where the real UAV flew would
make the plain KL infinite; additive pseudo-counts would instead depend on the number of cells
(on a 10 m grid over a 1 km field they outweigh the samples). The skew form needs no per-cell
constant and is bounded by log2(1 / lam) = 6.64 bits.
"""

from __future__ import annotations

import numpy as np
from scipy.stats import entropy, pearsonr

from uavcas.stats.divergence import hellinger, histogram, jsd

KL_SKEW = 0.01


def error_metrics(pred, meas) -> dict:
    p, m = np.asarray(pred, float), np.asarray(meas, float)
    e = p - m
    r = float(pearsonr(p, m)[0]) if p.size > 2 and np.std(p) > 0 and np.std(m) > 0 else float("nan")
    return {
        "n": int(e.size),
        "rmse_db": float(np.sqrt(np.mean(e**2))),
        "mae_db": float(np.mean(np.abs(e))),
        "median_ae_db": float(np.median(np.abs(e))),
        "bias_db": float(np.mean(e)),
        "r": r,
    }


def shared_edges(samples, width: float) -> np.ndarray:
    """Linear bins of `width` covering min..max of ALL samples (nothing is dropped)."""
    v = np.concatenate([np.asarray(s, float).ravel() for s in samples])
    if v.size == 0 or not np.all(np.isfinite(v)):
        raise ValueError("need finite values to bin")
    lo = np.floor(v.min() / width) * width
    hi = max(np.ceil(v.max() / width) * width, lo + width)
    if hi <= v.max():
        hi += width
    return np.arange(lo, hi + width / 2, width)


def jsd_on_shared_bins(a, b, width: float) -> tuple[float, np.ndarray]:
    edges = shared_edges([a, b], width)
    return jsd(histogram(a, edges), histogram(b, edges)), edges


def hellinger_on_shared_bins(a, b, edges: np.ndarray) -> float:
    return hellinger(histogram(a, edges), histogram(b, edges))


def spatial_kl_bits(real_xy: np.ndarray, sim_xy: np.ndarray, cell_m: float) -> float:
    """KL(real || sim) of (x, y) visit frequencies on a shared grid of `cell_m` cells."""
    ex = shared_edges([real_xy[:, 0], sim_xy[:, 0]], cell_m)
    ey = shared_edges([real_xy[:, 1], sim_xy[:, 1]], cell_m)
    hr, _, _ = np.histogram2d(real_xy[:, 0], real_xy[:, 1], bins=[ex, ey])
    hs, _, _ = np.histogram2d(sim_xy[:, 0], sim_xy[:, 1], bins=[ex, ey])
    p = hr.ravel() / hr.sum()
    q = hs.ravel() / hs.sum()
    return float(entropy(p, (1.0 - KL_SKEW) * q + KL_SKEW * p, base=2))
