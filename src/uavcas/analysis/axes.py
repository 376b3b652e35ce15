"""Internal diversity per configuration axis: benign flows at the two extreme values of an axis
(all other axes mixed), with a same-distribution baseline drawn at the high group's size (the
low group's runs split in halves, as `diversity.size_matched_baseline`).

Confounding: when the runs at the two extremes also differ in another axis (or in their attack
compositions, which shape benign traffic too), a difference cannot be put on the axis alone.
For each other axis the total-variation distance between its value distributions over the runs
of the low and the high group is computed; those at or above `CONFOUND_TV` are listed in
`confounded_with` ("axis:tv", highest first). TV 1 means the two groups share no value of it.
"""

from __future__ import annotations

import json
from pathlib import Path

import pandas as pd

from uavcas import schema
from uavcas.atomic import atomic_write_text
from uavcas.stats.divergence import DEFAULT_BINS, compare_pooled, flow_counts, log_bins

from .diversity import size_matched_baseline
from .iat import flow_iats

# The paper's pairs for categorical axes (table tab:internal_diversity); numeric axes use min/max.
CATEGORICAL_EXTREMES: dict[str, tuple[str, str]] = {
    "pathloss": ("logdist", "3gpp"),
    "mission": ("spiral", "random"),
}
CONFOUND_TV = 0.5
COLUMNS = (
    "axis", "low", "high", "n_runs_low", "n_runs_high", "n_flows_low", "n_flows_high", "hellinger",
    "hellinger_lo", "hellinger_hi", "jsd", "jsd_lo", "jsd_hi", "baseline_n_flows", "baseline_hellinger",
    "baseline_hellinger_hi", "baseline_jsd", "baseline_jsd_hi", "baseline_split", "confounded_with", "iat_source",
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


def _runs(df: pd.DataFrame) -> pd.DataFrame:
    """One row per run with its axis values (one row per flow without run ids)."""
    return df.drop_duplicates("run_id") if "run_id" in df.columns else df


def confounders(lo_runs: pd.DataFrame, hi_runs: pd.DataFrame, axis: str, axes) -> list[tuple[str, float]]:
    """Other axes whose distribution over runs differs between the groups: (axis, TV), TV >= CONFOUND_TV."""
    out = []
    for other in axes:
        if other == axis or other not in lo_runs.columns:
            continue
        p = lo_runs[other].astype(str).value_counts(normalize=True)
        q = hi_runs[other].astype(str).value_counts(normalize=True)
        tv = 0.5 * float(p.sub(q, fill_value=0.0).abs().sum())
        if tv >= CONFOUND_TV:
            out.append((other, round(tv, 3)))
    return sorted(out, key=lambda t: -t[1])


def axis_diversity(
    df: pd.DataFrame, n_bins: int = DEFAULT_BINS, n_boot: int = 200, seed: int = 0,
    axes: tuple[str, ...] = schema.AXIS_COLUMNS, iat_source: str = "packet", baseline_draws: int = 50,
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
        ia, ib = flow_iats(lo_df, source=iat_source), flow_iats(hi_df, source=iat_source)
        if not ia.per_flow or not ib.per_flow:
            continue
        edges = log_bins([ia.pooled, ib.pooled], n_bins)
        ca, cb = flow_counts(ia.per_flow, edges), flow_counts(ib.per_flow, edges)
        c = compare_pooled(ca, cb, n_boot, seed=seed)
        runs = lo_df["run_id"].to_numpy()[ia.rows] if "run_id" in lo_df.columns else None
        base = size_matched_baseline(ca, runs, len(cb), baseline_draws, 0.95, seed)
        lo_runs, hi_runs = _runs(lo_df), _runs(hi_df)
        conf = confounders(lo_runs, hi_runs, axis, axes)
        rows.append({"axis": axis, "low": ex[0], "high": ex[1], "n_runs_low": len(lo_runs), "n_runs_high": len(hi_runs),
                     "n_flows_low": len(lo_df), "n_flows_high": len(hi_df), "hellinger": c.hellinger,
                     "hellinger_lo": c.hellinger_lo, "hellinger_hi": c.hellinger_hi, "jsd": c.jsd, "jsd_lo": c.jsd_lo,
                     "jsd_hi": c.jsd_hi, "baseline_n_flows": base.n_flows, "baseline_hellinger": base.hellinger,
                     "baseline_hellinger_hi": base.hellinger_hi, "baseline_jsd": base.jsd,
                     "baseline_jsd_hi": base.jsd_hi, "baseline_split": base.split,
                     "confounded_with": ", ".join(f"{a}:{tv:.2f}" for a, tv in conf), "iat_source": ia.source})
        bins[axis] = edges.tolist()
    return pd.DataFrame(rows).reindex(columns=list(COLUMNS)), bins


def write_axes(out: str | Path, table: pd.DataFrame, edges, iat_source: str) -> list[Path]:
    """`uavcas analyze axes`'s files in `out`: axes.csv and axes.json (the IAT source, the confounding
    threshold, the bin edges, the table as records)."""
    out = Path(out)
    payload = {"iat_source": iat_source, "confound_tv": CONFOUND_TV, "bins": edges,
               "table": json.loads(table.to_json(orient="records"))}
    return [atomic_write_text(out / "axes.csv", table.to_csv(index=False)),
            atomic_write_text(out / "axes.json", json.dumps(payload, indent=2, default=str, allow_nan=True))]
