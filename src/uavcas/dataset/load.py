"""`uavcas.load_dataset`: a flow dataset as the four things a model needs.

    X, y, groups, meta = uavcas.load_dataset("ds", view="5tuple", features="cic")

- `X`: DataFrame of the feature columns only (a feature set, `uavcas.ids.features.feature_sets`:
  a feature standard's columns, for the window-host view, episodes, its own set; or the columns
  given; `context=True` adds the dataset's `ctx_*` context columns, what `baseline("context")`
  learns from); NaN and inf (CICFlowMeter's rates and IATs of a flow with a zero duration or one
  packet) handled by the `nonfinite` policy, recorded in `X.attrs["nonfinite"]`;
- `y`: the class of each flow (`label`, 'Benign' or an attack class);
- `groups`: the run of each flow (`run_id`), for grouped splits (`sklearn.model_selection.GroupKFold`
  or `uavcas.ids.splits.grouped_split`): flows of one run share its channel and timing;
- `meta`: every other column (ids, axes, per-family labels, counts, sequences), same index.
No metadata column is ever among the features.
"""

from __future__ import annotations

from collections.abc import Iterable
from pathlib import Path
from typing import Literal, NamedTuple

import numpy as np
import pandas as pd

from uavcas.ids.features import context_columns, context_matrix, resolve_features

from .read import load_any

Nonfinite = Literal["zero", "nan", "drop"]
NONFINITE: tuple[str, ...] = ("zero", "nan", "drop")


class Dataset(NamedTuple):
    X: pd.DataFrame
    y: pd.Series
    groups: pd.Series
    meta: pd.DataFrame


def load_dataset(path: str | Path, view: str | None = None, features: str | Iterable[str] | None = None,
                 fmt: str | None = None, context: bool = False, nonfinite: Nonfinite = "zero") -> Dataset:
    """Read `path` (any format `uavcas.dataset.read.load_any` reads; `fmt` names it when the path
    does not tell) and split it into features, labels, groups and metadata.

    `view` picks one flow view when the dataset holds several; `features` is a feature-set name
    (`ids.features.feature_sets`: a standard's name, e.g. 'cic'), a list of feature columns, or
    None for the dataset's own;
    `context` appends the context columns (`schema.CONTEXT_FEATURES`; an error when the dataset
    has none).

    `nonfinite`: what becomes of the NaN and +-inf feature values (CICFlowMeter's Flow Bytes/s,
    Flow Packets/s and IATs of a flow with a zero duration or a single packet, as CICIDS2017 has
    them; about half the rows of a short campaign):
    - "zero" (default): set to 0, what the benchmark does; every scikit-learn estimator fits it
      (a random forest refuses inf, and NaN before scikit-learn 1.4);
    - "nan": +-inf become NaN and NaN stays, for estimators with a missing-value rule
      (HistGradientBoosting, LightGBM);
    - "drop": rows with any non-finite feature are left out of X, y, groups and meta alike.
    `X.attrs["nonfinite"]` records the policy, the values it changed and the rows it touched
    (`{"policy": ..., "values": n, "rows": n, "rows_in": n}`).
    """
    if nonfinite not in NONFINITE:
        raise ValueError(f"nonfinite: {nonfinite!r} is not one of {', '.join(NONFINITE)}")
    df = load_any(path, fmt, view=view).reset_index(drop=True)
    if "label" not in df.columns:
        raise ValueError(f"{path}: no 'label' column")
    cols = resolve_features(df, features)
    if context:
        context_matrix(df.head(1))  # refuses a dataset without the columns
        cols = cols + [c for c in context_columns(df) if c not in cols]
    values = df[cols].to_numpy(dtype=np.float64, copy=True)
    bad = ~np.isfinite(values)
    bad_rows = bad.any(axis=1)
    record = {"policy": nonfinite, "values": int(bad.sum()), "rows": int(bad_rows.sum()), "rows_in": len(df)}
    if nonfinite == "drop":
        df, values = df[~bad_rows].reset_index(drop=True), values[~bad_rows]
    else:
        values[bad] = 0.0 if nonfinite == "zero" else np.nan
    X = pd.DataFrame(values, columns=cols, index=df.index)
    groups = df["run_id"].astype(str).rename("run_id") if "run_id" in df.columns else pd.Series(
        df.index.astype(str), index=df.index, name="run_id")
    meta = df.drop(columns=cols)
    X.attrs.update(df.attrs)
    X.attrs["nonfinite"] = record
    return Dataset(X, df["label"].astype(str).rename("label"), groups, meta)
