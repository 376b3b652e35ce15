"""Diversity table: each attack class vs Benign, bounded metrics + baseline + legacy columns.

Like for like:
- one IAT source (`iat.IAT_SOURCES`) for every dataset compared;
- the same-distribution baseline is drawn at the compared class's sample size: plug-in
  divergences are biased upward on small samples, so 12 benign flows against all benign flows
  score far above 0 although nothing differs. For each class of n flows, `baseline_draws` times:
  split the benign runs in two halves, draw n flows of one half, compare them with all flows of
  the other half (the class is compared with all benign flows the same way); the baseline is the
  mean over draws and `_hi` its upper percentile at `ci`.
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pandas as pd

from uavcas import schema, seeding
from uavcas.atomic import atomic_write_text
from uavcas.stats.divergence import (
    DEFAULT_BINS,
    compare_pairwise,
    compare_pooled,
    flow_counts,
    hellinger,
    jsd,
    log_bins,
)

from .iat import FlowIATs, flow_iats
from .legacy import legacy_divergence

COLUMNS = (
    "dataset", "class", "n_flows", "n_iats", "hellinger", "hellinger_lo", "hellinger_hi", "jsd",
    "jsd_lo", "jsd_hi", "baseline_n_flows", "baseline_hellinger", "baseline_hellinger_hi", "baseline_jsd",
    "baseline_jsd_hi", "hellinger_pairwise", "jsd_pairwise", "baseline_hellinger_pairwise",
    "baseline_jsd_pairwise", "legacy_hellinger", "legacy_jsd",
    "legacy_n_pairs", "iat_source",
)


@dataclass
class DiversityOptions:
    n_bins: int = DEFAULT_BINS
    n_boot: int = 200
    ci: float = 0.95
    seed: int = 0
    pairwise: bool = False
    pairwise_pairs: int = 2000
    legacy: bool = True
    iat_source: str = "packet"  # one of iat.IAT_SOURCES; the CLI picks it for all datasets at once
    baseline_draws: int = 50


@dataclass
class DiversityResult:
    table: pd.DataFrame
    bins: dict[str, list[float]] = field(default_factory=dict)
    info: dict[str, dict] = field(default_factory=dict)


def class_order(labels) -> list[str]:
    present = set(labels)
    known = [c for c in schema.CLASSES if c in present]
    return known + sorted(present - set(known))


def split_by_run(df: pd.DataFrame, seed: int) -> tuple[pd.DataFrame, pd.DataFrame, str]:
    """Two halves of `df` by run (no run on both sides); by flow when there is a single run."""
    a, b, by = halves(df["run_id"].to_numpy() if "run_id" in df.columns else None, len(df), seeding.generator(seed))
    return df[a], df[b], by


def halves(runs: np.ndarray | None, n: int, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray, str]:
    """Boolean masks of two halves of n rows, by run when there are >= 2 runs, else by row."""
    if runs is not None and len(np.unique(runs)) >= 2:
        uniq = np.unique(runs)
        first = rng.permutation(uniq)[: len(uniq) // 2]
        m = np.isin(runs, first)
        return m, ~m, "run"
    m = rng.permutation(n) < n // 2
    return m, ~m, "flow"


@dataclass(frozen=True)
class Baseline:
    n_flows: int
    hellinger: float
    hellinger_hi: float
    jsd: float
    jsd_hi: float
    split: str


def size_matched_baseline(counts: np.ndarray, runs: np.ndarray | None, n: int, draws: int, ci: float,
                          seed: int) -> Baseline:
    """Divergence of n reference flows against the rest of the reference, by run halves (see the
    module docstring). `counts`: per-flow IAT counts of the reference (benign) flows."""
    rng = seeding.generator(seed)
    hs, js, used, by = [], [], 0, "flow"
    for _ in range(draws):
        a, b, by = halves(runs, len(counts), rng)
        ia = np.flatnonzero(a)
        if not len(ia) or not b.any():
            continue
        k = min(n, len(ia))
        pa = counts[rng.choice(ia, k, replace=False)].sum(0)
        pb = counts[b].sum(0)
        if pa.sum() == 0 or pb.sum() == 0:
            continue
        hs.append(hellinger(pa, pb))
        js.append(jsd(pa, pb))
        used = k
    if not hs:
        return Baseline(0, np.nan, np.nan, np.nan, np.nan, by)
    q = 100 * (1 - (1 - ci) / 2)
    return Baseline(used, float(np.mean(hs)), float(np.percentile(hs, q)), float(np.mean(js)),
                    float(np.percentile(js, q)), by)


def _pairwise_baseline(benign: pd.DataFrame, edges: np.ndarray, opt: DiversityOptions) -> tuple[float, float]:
    # per-flow histograms are noisy: the pairwise view has its own, higher floor (by run halves)
    a, b, _ = split_by_run(benign, opt.seed)
    ca = flow_counts(flow_iats(a, source=opt.iat_source).per_flow, edges)
    cb = flow_counts(flow_iats(b, source=opt.iat_source).per_flow, edges)
    if ca.sum() == 0 or cb.sum() == 0:
        return np.nan, np.nan
    return compare_pairwise(ca, cb, opt.pairwise_pairs, opt.seed)


def diversity_table(df: pd.DataFrame, dataset: str = "dataset", opt: DiversityOptions | None = None) -> DiversityResult:
    """One row per non-benign class of `df` against its Benign flows."""
    opt = opt or DiversityOptions()
    if "label" not in df.columns:
        raise ValueError(f"{dataset}: no 'label' column")
    if not (df["label"] == schema.BENIGN).any():
        raise ValueError(f"{dataset}: no Benign flow to compare against")
    classes = class_order(df["label"].unique())
    iats: dict[str, FlowIATs] = {c: flow_iats(df[df["label"] == c], source=opt.iat_source) for c in classes}
    # one set of bins for the whole dataset: every class and the baseline on the same grid
    edges = log_bins([iats[c].pooled for c in classes if iats[c].per_flow], opt.n_bins)
    benign = df[df["label"] == schema.BENIGN]
    bi = iats[schema.BENIGN]
    cb = flow_counts(bi.per_flow, edges)
    # runs of the benign flows that have an IAT (the rows of cb), for run-wise baseline halves
    runs = benign["run_id"].to_numpy()[bi.rows] if "run_id" in benign.columns else None
    hp, jp = _pairwise_baseline(benign, edges, opt) if opt.pairwise else (np.nan, np.nan)
    rows, base_by = [], "flow"
    for c in classes:
        if c == schema.BENIGN:
            continue
        ca = flow_counts(iats[c].per_flow, edges)
        base = size_matched_baseline(cb, runs, len(ca), opt.baseline_draws, opt.ci, opt.seed)
        base_by = base.split
        row = {"dataset": dataset, "class": c, "n_flows": int((df["label"] == c).sum()),
               "n_iats": int(ca.sum()), "iat_source": iats[c].source, "baseline_n_flows": base.n_flows,
               "baseline_hellinger": base.hellinger, "baseline_hellinger_hi": base.hellinger_hi,
               "baseline_jsd": base.jsd, "baseline_jsd_hi": base.jsd_hi,
               "baseline_hellinger_pairwise": hp, "baseline_jsd_pairwise": jp}
        if ca.sum() == 0:
            rows.append(row)
            continue
        cmp = compare_pooled(ca, cb, opt.n_boot, opt.ci, opt.seed)
        row.update(hellinger=cmp.hellinger, hellinger_lo=cmp.hellinger_lo, hellinger_hi=cmp.hellinger_hi,
                   jsd=cmp.jsd, jsd_lo=cmp.jsd_lo, jsd_hi=cmp.jsd_hi)
        if opt.pairwise:
            row["hellinger_pairwise"], row["jsd_pairwise"] = compare_pairwise(ca, cb, opt.pairwise_pairs, opt.seed)
        if opt.legacy and opt.iat_source == "packet":  # the authors' metric is defined on per-packet IATs
            leg = legacy_divergence(iats[c].per_flow, bi.per_flow, seed=opt.seed)
            row.update(legacy_hellinger=leg.hellinger, legacy_jsd=leg.jsd, legacy_n_pairs=leg.n_pairs)
        rows.append(row)
    table = pd.DataFrame(rows).reindex(columns=list(COLUMNS))
    info = {
        "iat_source": bi.source,
        "baseline_split": base_by,
        "baseline_draws": opt.baseline_draws,
        "n_zero_iats": int(sum(v.n_zero for v in iats.values())),
        "n_negative_iats_clipped": int(sum(v.n_negative for v in iats.values())),
        "n_flows_without_iat": int(sum(v.n_flows_no_iat for v in iats.values())),
    }
    return DiversityResult(table, {dataset: edges.tolist()}, {dataset: info})


def write_diversity(out: str | Path, table: pd.DataFrame, opt: DiversityOptions,
                    results: list[DiversityResult]) -> list[Path]:
    """`uavcas analyze diversity`'s files in `out`: diversity.csv (the table of every dataset) and
    diversity.json (the options, each dataset's bins and info, the table as records)."""
    out = Path(out)
    payload: dict = {"options": vars(opt), "bins": {}, "info": {}}
    for res in results:
        payload["bins"].update(res.bins)
        payload["info"].update(res.info)
    payload["table"] = json.loads(table.to_json(orient="records"))
    return [atomic_write_text(out / "diversity.csv", table.to_csv(index=False)),
            atomic_write_text(out / "diversity.json", json.dumps(payload, indent=2, default=str, allow_nan=True))]
