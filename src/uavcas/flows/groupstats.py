"""Grouped summary statistics over values sorted by a non-decreasing group id (numpy only)."""

from __future__ import annotations

import numpy as np


class GroupStats:
    """count/sum/mean/std/var/min/max of `values` grouped by `group` (non-decreasing, in [0, n)).

    `ddof` 1 gives the sample statistics (Apache commons-math SummaryStatistics, CICFlowMeter),
    0 the population ones (numpy's default, the authors' generator). Statistics of an empty
    group are `empty` (0 or NaN, as the caller's standard wants); a one-value group has std 0.
    """

    def __init__(self, values: np.ndarray, group: np.ndarray, n: int, ddof: int = 1, empty: float = 0.0):
        v = values.astype(np.float64)
        self.count = np.bincount(group, minlength=n).astype(np.float64)
        self.sum = np.bincount(group, weights=v, minlength=n)
        has = self.count > 0
        with np.errstate(invalid="ignore", divide="ignore"):
            mean = self.sum / np.maximum(self.count, 1)
            dev = np.bincount(group, weights=(v - mean[group]) ** 2, minlength=n)
            var = np.where(self.count > ddof, dev / np.maximum(self.count - ddof, 1), 0.0)
        self.mean = np.where(has, mean, empty)
        self.var = np.where(has, var, empty)
        self.std = np.where(has, np.sqrt(var), empty)
        self.max = np.full(n, empty)
        self.min = np.full(n, empty)
        if v.shape[0]:
            starts = np.flatnonzero(np.concatenate(([True], group[1:] != group[:-1])))
            present = group[starts]
            self.max[present] = np.maximum.reduceat(v, starts)
            self.min[present] = np.minimum.reduceat(v, starts)


def gaps(t: np.ndarray, group: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Consecutive differences of `t` within each group, and the group of each difference."""
    same = group[1:] == group[:-1]
    return np.diff(t)[same], group[1:][same]


def direction_stats(fw: GroupStats, bw: GroupStats, fiat: GroupStats, biat: GroupStats,
                    iat_max: bool) -> dict[str, np.ndarray]:
    """The per-direction length and IAT statistics both feature standards share (same names).

    IAT statistics need two packets in the direction (0 otherwise); `iat_max` adds Fwd/Bwd IAT Max.
    """
    out: dict[str, np.ndarray] = {}
    for side, s in (("Fwd", fw), ("Bwd", bw)):
        out.update({f"{side} Packet Length Max": s.max, f"{side} Packet Length Min": s.min,
                    f"{side} Packet Length Mean": s.mean, f"{side} Packet Length Std": s.std})  # fmt: skip
    for side, s, pk in (("Fwd", fiat, fw), ("Bwd", biat, bw)):
        two = pk.count > 1
        out.update({f"{side} IAT Total": np.where(two, s.sum, 0.0), f"{side} IAT Mean": np.where(two, s.mean, 0.0),
                    f"{side} IAT Std": np.where(two, s.std, 0.0)})  # fmt: skip
        if iat_max:
            out[f"{side} IAT Max"] = np.where(two, s.max, 0.0)
    return out


def length_and_flag_stats(lens: GroupStats, g: np.ndarray, flags: np.ndarray, bits, n: int) -> dict[str, np.ndarray]:
    """Min/Max/Mean/Std/Variance of the packet lengths and one count per (name, TCP flag bit)."""
    out = {"Min Packet Length": lens.min, "Max Packet Length": lens.max, "Packet Length Mean": lens.mean,
           "Packet Length Std": lens.std, "Packet Length Variance": lens.var}  # fmt: skip
    for name, bit in bits:
        out[name] = np.bincount(g, weights=((flags & bit) != 0).astype(np.float64), minlength=n)
    return out
