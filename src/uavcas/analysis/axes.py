"""Internal diversity per configuration axis: benign flows at the two extreme values of an axis
(all other axes mixed), with a same-distribution baseline (the low-value group split by run)."""

from __future__ import annotations

import numpy as np
import pandas as pd

from uavcas import schema
from uavcas.stats.divergence import DEFAULT_BINS, compare_pooled, flow_counts, log_bins

from .diversity import split_by_run
from .iat import flow_iats

# The paper's pairs for categorical axes (table tab:internal_diversity); numeric axes use min/max.
CATEGORICAL_EXTREMES: dict[str, tuple[str, str]] = {
    "pathloss": ("logdist", "3gpp"),
    "mission": ("spiral", "random"),
}
COLUMNS = (
    "axis", "low", "high", "n_flows_low", "n_flows_high", "hellinger", "hellinger_lo",
    "hellinger_hi", "jsd", "jsd_lo", "jsd_hi", "baseline_hellinger", "baseline_jsd", "baseline_split",
)


def extremes(values: pd.Series, axis: str) -> tuple[object, object] | None:
    present = [v for v in pd.unique(values.dropna())]
    if len(present) < 2:
        return None
    if axis in CATEGORICAL_EXTREMES and set(CATEGORICAL_EXTREMES[axis]) <= set(map(str, present)):
        lo, hi = CATEGORICAL_EXTREMES[axis]
        return type(present[0])(lo), type(present[0])(hi)
    if pd.api.types.is_numeric_dtype(values):
        return min(present), max(present)
    s = sorted(map(str, present))
    return s[0], s[-1]


def axis_diversity(
    df: pd.DataFrame, n_bins: int = DEFAULT_BINS, n_boot: int = 200, seed: int = 0,
    axes: tuple[str, ...] = schema.AXIS_COLUMNS,
) -> tuple[pd.DataFrame, dict[str, list[float]]]:
    """One row per axis with >= 2 values among benign flows; returns (table, bins per axis)."""
    if "label" not in df.columns:
        raise ValueError("no 'label' column")
    benign = df[df["label"] == schema.BENIGN]
    if benign.empty:
        raise ValueError("no Benign flow: internal diversity is computed on benign flows")
    rows, bins = [], {}
    for axis in axes:
        if axis not in benign.columns or axis == "attacks":  # attacks is the class mix, not a condition
            continue
        ex = extremes(benign[axis], axis)
        if ex is None:
            continue
        lo_df = benign[benign[axis] == ex[0]]
        hi_df = benign[benign[axis] == ex[1]]
        ia, ib = flow_iats(lo_df), flow_iats(hi_df)
        if not ia.per_flow or not ib.per_flow:
            continue
        edges = log_bins([ia.pooled, ib.pooled], n_bins)
        c = compare_pooled(flow_counts(ia.per_flow, edges), flow_counts(ib.per_flow, edges), n_boot, seed=seed)
        b1, b2, by = split_by_run(lo_df, seed)
        p1, p2 = flow_iats(b1).per_flow, flow_iats(b2).per_flow
        if p1 and p2:
            bc = compare_pooled(flow_counts(p1, edges), flow_counts(p2, edges), n_boot=0, seed=seed)
            base_h, base_j = bc.hellinger, bc.jsd
        else:
            base_h = base_j = np.nan
        rows.append({"axis": axis, "low": ex[0], "high": ex[1], "n_flows_low": len(lo_df),
                     "n_flows_high": len(hi_df), "hellinger": c.hellinger, "hellinger_lo": c.hellinger_lo,
                     "hellinger_hi": c.hellinger_hi, "jsd": c.jsd, "jsd_lo": c.jsd_lo, "jsd_hi": c.jsd_hi,
                     "baseline_hellinger": base_h, "baseline_jsd": base_j, "baseline_split": by})
        bins[axis] = edges.tolist()
    return pd.DataFrame(rows).reindex(columns=list(COLUMNS)), bins
