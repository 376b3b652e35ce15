"""Bounded divergences between two samples' distributions on shared, recorded bins.

Used by the analyses (IAT distributions on log-spaced bins, `log_bins`, bootstrapped over flows)
and by the calibration (measured vs simulated link quantities on its own linear bins).

Both metrics are in [0, 1]:
- Hellinger distance H(p, q) = ||sqrt(p) - sqrt(q)||_2 / sqrt(2).
- Jensen–Shannon divergence with base-2 logarithms, JSD(p, q) = jensenshannon(p, q, base=2) ** 2
  (scipy returns the JS *distance*, the square root of the divergence).

`log_bins`: edge 0 followed by `n_bins` geometric edges from the smallest to the largest
positive value of all samples compared, so every value (zero IATs included, see
`uavcas.analysis.iat`) falls in a bin and the bins scale with the data (changing the time unit
changes nothing). Bootstrap resamples *flows*
(IATs inside a flow are dependent), seeded; intervals are percentile intervals. Plug-in
divergences are biased upward on finite samples (two samples of one distribution do not give 0,
and a resample of them gives more): read a value against the same-distribution baseline, not 0.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from scipy.spatial.distance import euclidean, jensenshannon

from uavcas import seeding

DEFAULT_BINS = 50


def log_bins(samples: Sequence[np.ndarray], n_bins: int = DEFAULT_BINS) -> np.ndarray:
    """Shared edges covering every value of `samples`: [0, lo, ..., hi] (n_bins log-spaced bins
    above a first bin [0, lo) that holds zero IATs)."""
    if n_bins < 1:
        raise ValueError(f"n_bins must be >= 1, got {n_bins}")
    values = np.concatenate([np.asarray(s, dtype=float).ravel() for s in samples] or [np.empty(0)])
    if values.size == 0:
        raise ValueError("no values to bin")
    if not np.all(np.isfinite(values)) or np.any(values < 0):
        raise ValueError("IATs must be finite and >= 0 (clip negatives explicitly, see iat.py)")
    pos = values[values > 0]
    if pos.size == 0:  # all zero: one degenerate positive range so the edges stay increasing
        lo, hi = 1.0, 2.0
    else:
        lo, hi = float(pos.min()), float(pos.max())
        if hi <= lo:
            hi = lo * 2.0
    return np.concatenate([[0.0], np.geomspace(lo, hi, n_bins + 1)])


def bin_index(values: np.ndarray, edges: np.ndarray) -> np.ndarray:
    """Bin of each value (np.histogram's convention: last bin closed); errors if any is outside."""
    v = np.asarray(values, dtype=float)
    if v.size and (v.min() < edges[0] or v.max() > edges[-1]):
        raise ValueError(
            f"values outside the bins [{edges[0]:g}, {edges[-1]:g}]: compute the bins on all data"
        )
    idx = np.searchsorted(edges, v, side="right") - 1
    return np.minimum(idx, len(edges) - 2)


def histogram(values: np.ndarray, edges: np.ndarray) -> np.ndarray:
    """Probability mass per bin (sums to 1)."""
    counts = np.bincount(bin_index(values, edges), minlength=len(edges) - 1).astype(float)
    total = counts.sum()
    if total == 0:
        raise ValueError("empty sample: no IAT to compare")
    return counts / total


def _check_pq(p: np.ndarray, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    p = np.asarray(p, dtype=float)
    q = np.asarray(q, dtype=float)
    if p.shape != q.shape:
        raise ValueError(f"histograms on different bins: {p.shape} vs {q.shape}")
    if np.any(p < 0) or np.any(q < 0) or p.sum() <= 0 or q.sum() <= 0:
        raise ValueError("histograms must be non-negative with positive mass")
    return p / p.sum(), q / q.sum()


def hellinger(p: np.ndarray, q: np.ndarray) -> float:
    """Hellinger distance of two histograms on the same bins, in [0, 1]."""
    p, q = _check_pq(p, q)
    return float(min(1.0, euclidean(np.sqrt(p), np.sqrt(q)) / np.sqrt(2.0)))


def jsd(p: np.ndarray, q: np.ndarray) -> float:
    """Jensen–Shannon divergence (base 2) of two histograms on the same bins, in [0, 1]."""
    p, q = _check_pq(p, q)
    d = jensenshannon(p, q, base=2.0)
    return float(min(1.0, max(0.0, d * d)))


def flow_counts(per_flow: Sequence[np.ndarray], edges: np.ndarray) -> np.ndarray:
    """(n_flows, n_bins) IAT counts, one row per flow: the unit the bootstrap resamples."""
    nb = len(edges) - 1
    if not per_flow:
        return np.zeros((0, nb))
    lengths = np.array([len(f) for f in per_flow])
    flow = np.repeat(np.arange(len(per_flow)), lengths)
    idx = bin_index(np.concatenate(per_flow), edges)
    return np.bincount(flow * nb + idx, minlength=len(per_flow) * nb).reshape(len(per_flow), nb)


@dataclass(frozen=True)
class Comparison:
    """Pooled divergences of two flow sets with bootstrap percentile intervals."""

    hellinger: float
    jsd: float
    hellinger_lo: float
    hellinger_hi: float
    jsd_lo: float
    jsd_hi: float
    n_flows_a: int
    n_flows_b: int
    n_iats_a: int
    n_iats_b: int


def compare_pooled(
    counts_a: np.ndarray,
    counts_b: np.ndarray,
    n_boot: int = 200,
    ci: float = 0.95,
    seed: int = 0,
) -> Comparison:
    """Divergences of the pooled IAT histograms of two flow sets (rows of per-flow counts)."""
    if counts_a.sum() == 0 or counts_b.sum() == 0:
        raise ValueError("a side of the comparison has no IAT")
    pa, pb = counts_a.sum(0), counts_b.sum(0)
    h, j = hellinger(pa, pb), jsd(pa, pb)
    rng = seeding.generator(seed)
    hs, js = [], []
    for _ in range(n_boot):
        ra = counts_a[rng.integers(0, len(counts_a), len(counts_a))].sum(0)
        rb = counts_b[rng.integers(0, len(counts_b), len(counts_b))].sum(0)
        if ra.sum() == 0 or rb.sum() == 0:
            continue
        hs.append(hellinger(ra, rb))
        js.append(jsd(ra, rb))
    alpha = (1.0 - ci) / 2.0
    q = [100 * alpha, 100 * (1 - alpha)]
    h_lo, h_hi = np.percentile(hs, q) if hs else (np.nan, np.nan)
    j_lo, j_hi = np.percentile(js, q) if js else (np.nan, np.nan)
    return Comparison(
        h, j, float(h_lo), float(h_hi), float(j_lo), float(j_hi),
        len(counts_a), len(counts_b), int(counts_a.sum()), int(counts_b.sum()),
    )


def compare_pairwise(
    counts_a: np.ndarray, counts_b: np.ndarray, n_pairs: int = 2000, seed: int = 0
) -> tuple[float, float]:
    """Mean Hellinger and JSD over random (flow of a, flow of b) pairs, each flow's own histogram
    on the shared bins (the per-flow view, bounded, as an option beside the pooled one)."""
    a = counts_a[counts_a.sum(1) > 0]
    b = counts_b[counts_b.sum(1) > 0]
    if len(a) == 0 or len(b) == 0:
        raise ValueError("a side of the comparison has no flow with an IAT")
    rng = seeding.generator(seed)
    pa = a[rng.integers(0, len(a), n_pairs)].astype(float)
    pb = b[rng.integers(0, len(b), n_pairs)].astype(float)
    pa /= pa.sum(1, keepdims=True)
    pb /= pb.sum(1, keepdims=True)
    h = np.sqrt(np.clip(0.5 * ((np.sqrt(pa) - np.sqrt(pb)) ** 2).sum(1), 0.0, 1.0))
    j = jensenshannon(pa, pb, base=2.0, axis=1) ** 2
    return float(h.mean()), float(np.clip(j, 0.0, 1.0).mean())
