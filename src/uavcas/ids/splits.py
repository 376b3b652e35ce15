"""Train/validation/test splits, stratified by class AND grouped by run (no run in two splits).

Flow-level random splits (the authors') put flows of one run on both sides; flows of a run share
its channel and timing, so the test score then measures memorisation of runs.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from sklearn.model_selection import StratifiedGroupKFold


@dataclass(frozen=True)
class Split:
    train: np.ndarray
    val: np.ndarray
    test: np.ndarray


def _one_fold(y: np.ndarray, groups: np.ndarray, n_splits: int, seed: int) -> tuple[np.ndarray, np.ndarray]:
    """(rest, held) indices: one fold of a shuffled StratifiedGroupKFold."""
    n_groups = len(np.unique(groups))
    if n_groups < 2:
        raise ValueError(f"need at least 2 runs to split by run, got {n_groups}")
    k = min(n_splits, n_groups)
    # sklearn warns when a class has fewer members than folds; harmless for a single fold
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)
        cv = StratifiedGroupKFold(n_splits=k, shuffle=True, random_state=seed)
        rest, held = next(cv.split(np.zeros(len(y)), y, groups))
    return rest, held


def grouped_split(y, groups, test: float = 0.2, val: float = 0.1, seed: int = 0) -> Split:
    """70/10/20 (by default) split; fractions are met up to the granularity of runs."""
    y = np.asarray(y)
    groups = np.asarray(groups)
    if not (0 < test < 1 and 0 <= val < 1 and test + val < 1):
        raise ValueError(f"bad split fractions test={test} val={val}")
    rest, te = _one_fold(y, groups, max(2, round(1 / test)), seed)
    if val > 0:
        # val is a fraction of the whole; within the rest it is val / (1 - test)
        r_tr, r_va = _one_fold(y[rest], groups[rest], max(2, round((1 - test) / val)), seed + 1)
        tr, va = rest[r_tr], rest[r_va]
    else:
        tr, va = rest, np.empty(0, dtype=int)
    g_tr, g_va, g_te = set(groups[tr]), set(groups[va]), set(groups[te])
    if g_tr & g_te or g_va & g_te or g_tr & g_va:  # cannot happen with group folds; guard anyway
        raise AssertionError("a run is in two splits")
    return Split(np.sort(tr), np.sort(va), np.sort(te))
