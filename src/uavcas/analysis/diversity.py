"""Diversity table: each attack class vs Benign, bounded metrics + baseline + legacy columns."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import pandas as pd

from uavcas import schema
from uavcas.stats.divergence import DEFAULT_BINS, compare_pairwise, compare_pooled, flow_counts, log_bins

from .iat import FlowIATs, flow_iats, iat_source
from .legacy import legacy_divergence

COLUMNS = (
    "dataset", "class", "n_flows", "n_iats", "hellinger", "hellinger_lo", "hellinger_hi", "jsd",
    "jsd_lo", "jsd_hi", "baseline_hellinger", "baseline_hellinger_hi", "baseline_jsd",
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
    rng = np.random.default_rng(seed)
    if "run_id" in df.columns and df["run_id"].nunique() >= 2:
        runs = np.array(sorted(df["run_id"].unique()))
        rng.shuffle(runs)
        first = set(runs[: len(runs) // 2])
        m = df["run_id"].isin(first).to_numpy()
        return df[m], df[~m], "run"
    m = rng.permutation(len(df)) < len(df) // 2
    return df[m], df[~m], "flow"


def _baseline(benign: pd.DataFrame, edges: np.ndarray, opt: DiversityOptions) -> tuple[dict, str]:
    a, b, by = split_by_run(benign, opt.seed)
    ca, cb = flow_counts(flow_iats(a).per_flow, edges), flow_counts(flow_iats(b).per_flow, edges)
    if ca.sum() == 0 or cb.sum() == 0:
        return {k: np.nan for k in ("h", "h_hi", "j", "j_hi", "hp", "jp")}, by
    c = compare_pooled(ca, cb, opt.n_boot, opt.ci, opt.seed)
    out = {"h": c.hellinger, "h_hi": c.hellinger_hi, "j": c.jsd, "j_hi": c.jsd_hi, "hp": np.nan, "jp": np.nan}
    if opt.pairwise:  # per-flow histograms are noisy: the pairwise view has its own, higher floor
        out["hp"], out["jp"] = compare_pairwise(ca, cb, opt.pairwise_pairs, opt.seed)
    return out, by


def diversity_table(df: pd.DataFrame, dataset: str = "dataset", opt: DiversityOptions | None = None) -> DiversityResult:
    """One row per non-benign class of `df` against its Benign flows."""
    opt = opt or DiversityOptions()
    if "label" not in df.columns:
        raise ValueError(f"{dataset}: no 'label' column")
    if not (df["label"] == schema.BENIGN).any():
        raise ValueError(f"{dataset}: no Benign flow to compare against")
    classes = class_order(df["label"].unique())
    iats: dict[str, FlowIATs] = {c: flow_iats(df[df["label"] == c]) for c in classes}
    # one set of bins for the whole dataset: every class and the baseline on the same grid
    edges = log_bins([iats[c].pooled for c in classes if iats[c].per_flow], opt.n_bins)
    benign = df[df["label"] == schema.BENIGN]
    base, base_by = _baseline(benign, edges, opt)
    cb = flow_counts(iats[schema.BENIGN].per_flow, edges)
    rows = []
    for c in classes:
        if c == schema.BENIGN:
            continue
        ca = flow_counts(iats[c].per_flow, edges)
        row = {"dataset": dataset, "class": c, "n_flows": int((df["label"] == c).sum()),
               "n_iats": int(ca.sum()), "iat_source": iat_source(df),
               "baseline_hellinger": base["h"], "baseline_hellinger_hi": base["h_hi"],
               "baseline_jsd": base["j"], "baseline_jsd_hi": base["j_hi"],
               "baseline_hellinger_pairwise": base["hp"], "baseline_jsd_pairwise": base["jp"]}
        if ca.sum() == 0:
            rows.append(row)
            continue
        cmp = compare_pooled(ca, cb, opt.n_boot, opt.ci, opt.seed)
        row.update(hellinger=cmp.hellinger, hellinger_lo=cmp.hellinger_lo, hellinger_hi=cmp.hellinger_hi,
                   jsd=cmp.jsd, jsd_lo=cmp.jsd_lo, jsd_hi=cmp.jsd_hi)
        if opt.pairwise:
            row["hellinger_pairwise"], row["jsd_pairwise"] = compare_pairwise(ca, cb, opt.pairwise_pairs, opt.seed)
        if opt.legacy:
            leg = legacy_divergence(iats[c].per_flow, iats[schema.BENIGN].per_flow, seed=opt.seed)
            row.update(legacy_hellinger=leg.hellinger, legacy_jsd=leg.jsd, legacy_n_pairs=leg.n_pairs)
        rows.append(row)
    table = pd.DataFrame(rows).reindex(columns=list(COLUMNS))
    info = {
        "iat_source": iat_source(df),
        "baseline_split": base_by,
        "n_zero_iats": int(sum(v.n_zero for v in iats.values())),
        "n_negative_iats_clipped": int(sum(v.n_negative for v in iats.values())),
        "n_flows_without_iat": int(sum(v.n_flows_no_iat for v in iats.values())),
    }
    return DiversityResult(table, {dataset: edges.tolist()}, {dataset: info})
