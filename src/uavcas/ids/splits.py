"""Train/validation/test splits grouped by run (no run in two splits), stratified by composition,
one per seed, refusing splits that cannot score every declared class.

Flow-level random splits (the authors') put flows of one run on both sides; flows of a run share
its channel and timing, so the test score then measures memorisation of runs. Runs are therefore
the unit: within each stratum (a run's attack composition, or the set of classes it holds) the
runs are shuffled with the seed and dealt: `test` of them (at least one when the stratum has two)
to test, then `val` of all runs to validation from strata that keep a run for training, the rest
to training. Fractions are of runs, met up to the granularity of runs. Every declared class must
end up in training and in test; a class held by fewer than two runs cannot, and is refused with
its name and run count (`DegenerateSplitError`) instead of reporting a score on a test set that
never contains it.

External datasets have no runs: each flow is its own group and its label its stratum, which makes
this a stratified flow-level split.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pandas as pd

from uavcas import seeding

MIN_RUNS = 2  # one run to train on, one to test on


class DegenerateSplitError(ValueError):
    """A declared class cannot be both trained on and tested on."""


@dataclass(frozen=True)
class Split:
    """Row indices of each part (sorted) and the groups (runs) of each part."""

    train: np.ndarray
    val: np.ndarray
    test: np.ndarray
    groups: dict[str, tuple[str, ...]]


def runs_per_class(y, groups) -> pd.Series:
    """Number of distinct groups holding each class."""
    return pd.DataFrame({"y": np.asarray(y), "g": np.asarray(groups)}).drop_duplicates().groupby("y")["g"].size()


def check_declared(y, groups, declared, where: str = "") -> None:
    """Refuse when a declared class is held by fewer than MIN_RUNS runs (or none)."""
    counts = runs_per_class(y, groups)
    short = [(c, int(counts.get(c, 0))) for c in declared if counts.get(c, 0) < MIN_RUNS]
    if short:
        listed = ", ".join(f"{c} is in {n} run{'s' if n != 1 else ''}" for c, n in short)
        raise DegenerateSplitError(
            f"degenerate split{where}: {listed}; every declared class needs >= {MIN_RUNS} runs "
            "(one to train on, one to test on)"
        )


def _deal(strata: dict[str, list[str]], n_groups: int, test: float, val: float,
          rng: np.random.Generator) -> dict[str, str]:
    """group -> 'train' | 'val' | 'test'."""
    part: dict[str, str] = {}
    rest: dict[str, list[str]] = {}
    for key in sorted(strata):
        members = list(rng.permutation(np.array(strata[key], dtype=object)))
        n = len(members)
        if n == 1:  # a lone run: test with probability `test`, so the fraction holds on average
            part[members[0]] = "test" if rng.random() < test else "train"
            if part[members[0]] == "train":
                rest[key] = members
            continue
        k = min(max(1, int(round(test * n))), n - 1)
        for g in members[:k]:
            part[g] = "test"
        rest[key] = members[k:]
    target = int(round(val * n_groups))
    left = {k: len(v) for k, v in rest.items()}
    candidates = [(k, g) for k, v in rest.items() for g in v]
    n_val = 0
    for i in rng.permutation(len(candidates)):
        if n_val >= target:
            break
        k, g = candidates[i]
        if left[k] > 1:  # every stratum keeps a run for training
            part[g] = "val"
            left[k] -= 1
            n_val += 1
    for v in rest.values():
        for g in v:
            part.setdefault(g, "train")
    return part


def _repair(part: dict[str, str], classes_of: dict[str, set], declared, rng) -> None:
    """Move runs so that every declared class is in train and in test (needed when strata and
    classes differ, e.g. a composition whose runs hold different sets of classes)."""
    wanted = set(declared)
    count = {s: {c: 0 for c in wanted} for s in ("train", "val", "test")}
    for g, side in part.items():
        for c in classes_of[g] & wanted:
            count[side][c] += 1

    def can_leave(g: str, side: str) -> bool:
        return side == "val" or all(count[side][d] > 1 for d in classes_of[g] & wanted)

    for c in declared:
        for need, give in (("test", ("train", "val")), ("train", ("val", "test"))):
            if count[need][c]:
                continue
            for side in give:
                movable = sorted(g for g, s in part.items() if s == side and c in classes_of[g] and can_leave(g, side))
                if movable:
                    g = movable[int(rng.integers(len(movable)))]
                    part[g] = need
                    for d in classes_of[g] & wanted:
                        count[side][d] -= 1
                        count[need][d] += 1
                    break


def grouped_split(y, groups, seed: int = 0, test: float = 0.2, val: float = 0.1, strata=None,
                  declared=None) -> Split:
    """A seeded train/val/test split by group, stratified by `strata` (one value per row,
    constant within a group; default: the set of classes the group holds).

    `declared` (default: every class in `y`) must each be held by >= 2 groups; the split puts
    every declared class in train and in test, or raises DegenerateSplitError.
    """
    y = np.asarray(y).astype(str)
    groups = np.asarray(groups).astype(str)
    if not (0 < test < 1 and 0 <= val < 1 and test + val < 1):
        raise ValueError(f"bad split fractions test={test} val={val}")
    uniq = np.unique(groups)
    if len(uniq) < 2:
        raise ValueError(f"need at least 2 runs to split by run, got {len(uniq)}")
    declared = sorted(set(y)) if declared is None else list(declared)
    check_declared(y, groups, declared)
    pairs = pd.DataFrame({"g": groups, "y": y}).drop_duplicates()
    classes_of = {g: set(v) for g, v in pairs.groupby("g")["y"]}
    if strata is None:
        key_of = {g: "|".join(sorted(c)) for g, c in classes_of.items()}
    else:
        st = pd.DataFrame({"g": groups, "s": np.asarray(strata).astype(str)}).drop_duplicates("g")
        key_of = dict(zip(st["g"], st["s"]))
    by_key: dict[str, list[str]] = {}
    for g in uniq:
        by_key.setdefault(key_of[g], []).append(g)
    rng = seeding.generator(seed)
    part = _deal(by_key, len(uniq), test, val, rng)
    _repair(part, classes_of, declared, rng)
    for c in declared:
        for side in ("train", "test"):
            if not any(s == side and c in classes_of[g] for g, s in part.items()):
                n = sum(c in v for v in classes_of.values())
                raise DegenerateSplitError(f"degenerate split: no {side} run holds {c} ({n} runs hold it)")
    side_of_row = pd.Series(part).reindex(groups).to_numpy()
    idx = {s: np.flatnonzero(side_of_row == s) for s in ("train", "val", "test")}
    members = {s: tuple(sorted(g for g, p in part.items() if p == s)) for s in ("train", "val", "test")}
    return Split(idx["train"], idx["val"], idx["test"], members)


def cap_rows(rows: np.ndarray, y: np.ndarray, groups: np.ndarray, cap: int, seed: int) -> np.ndarray:
    """At most `cap` of `rows` per (run, class), a seeded sample, sorted: bounds the cost of
    training on floods (thousands of near-identical SYN flows per run) while keeping every run
    and class; test rows are never capped."""
    if cap is None or len(rows) == 0:
        return rows
    df = pd.DataFrame({"r": rows, "g": groups[rows], "y": y[rows]})
    rng = seeding.generator(seed)
    df["k"] = rng.random(len(df))
    kept = df.sort_values("k").groupby(["g", "y"], sort=False).head(cap)
    return np.sort(kept["r"].to_numpy())
