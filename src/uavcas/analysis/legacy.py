"""`legacy`: the authors' diversity computation, kept only to reproduce their table.

NOT a divergence in the usual sense (unbounded, bin-dependent, unit-dependent). Reconstructed from
the review of their code (../shared/docs/PAPER.md, "Diversity" row):
- flows with >= 100 packets; each flow's first 5,000 IATs;
- up to 200 flows of each side, every (a, b) pair of them (200 x 200), seeded choice;
- per flow a 50-bin histogram on *its own* range with `density=True` (so bins of two flows do
  not line up and the values are densities in 1/s, which grow as the IATs shrink);
- "Hellinger" = sqrt(0.5 * sum((sqrt(p) - sqrt(q))^2)) on those densities, compared bin index
  by bin index: far above 1 for fast floods (their 276);
- "JSD" = symmetric KL, 0.5 * (KL(p||q) + KL(q||p)), natural log, on the per-flow histograms
  normalised to mass 1 with eps = 1e-10 added (their 7-21, above the JSD's bound of ln 2 / 1).
Values are means over the pairs.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from uavcas import seeding

LEGACY_MIN_PACKETS = 100
LEGACY_MAX_IATS = 5000
LEGACY_FLOWS = 200
LEGACY_BINS = 50
LEGACY_EPS = 1e-10


@dataclass(frozen=True)
class LegacyResult:
    hellinger: float
    jsd: float
    n_pairs: int


def _per_flow(flows: Sequence[np.ndarray], rng: np.random.Generator, n_flows: int) -> list[np.ndarray]:
    # >= 100 packets means >= 99 IATs
    eligible = [f[:LEGACY_MAX_IATS] for f in flows if len(f) + 1 >= LEGACY_MIN_PACKETS]
    if len(eligible) > n_flows:
        pick = rng.choice(len(eligible), n_flows, replace=False)
        eligible = [eligible[i] for i in sorted(pick)]
    return eligible


def _hists(flows: list[np.ndarray]) -> tuple[np.ndarray, np.ndarray]:
    dens, mass = [], []
    for f in flows:
        d, _ = np.histogram(f, bins=LEGACY_BINS, density=True)
        c, _ = np.histogram(f, bins=LEGACY_BINS)
        dens.append(np.nan_to_num(d))  # an all-equal flow has zero range: numpy gives nan
        mass.append(c / max(c.sum(), 1))
    return np.array(dens), np.array(mass)


def legacy_divergence(
    flows_a: Sequence[np.ndarray], flows_b: Sequence[np.ndarray], seed: int = 0,
    n_flows: int = LEGACY_FLOWS,
) -> LegacyResult:
    """Mean legacy "Hellinger" and "JSD" over all pairs; NaN (n_pairs 0) when a side has no flow
    of >= 100 packets."""
    rng = seeding.generator(seed)
    a = _per_flow(flows_a, rng, n_flows)
    b = _per_flow(flows_b, rng, n_flows)
    if not a or not b:
        return LegacyResult(float("nan"), float("nan"), 0)
    da, ma = _hists(a)
    db, mb = _hists(b)
    # all pairs at once: (n_a, 1, bins) against (1, n_b, bins)
    h = np.sqrt(0.5 * ((np.sqrt(da)[:, None, :] - np.sqrt(db)[None, :, :]) ** 2).sum(-1))
    p = ma[:, None, :] + LEGACY_EPS
    q = mb[None, :, :] + LEGACY_EPS
    skl = 0.5 * ((p * np.log(p / q)).sum(-1) + (q * np.log(q / p)).sum(-1))
    return LegacyResult(float(h.mean()), float(skl.mean()), int(h.size))
