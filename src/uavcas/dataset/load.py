"""`uavcas.load_dataset`: a flow dataset as the four things a model needs.

    X, y, groups, meta = uavcas.load_dataset("ds", view="5tuple", features="cic")

- `X`: DataFrame of the feature columns only (a feature set of `uavcas.schema`: for the window-host
  view, episodes, its own set `schema.EPISODE_FEATURE_SETS`; or the columns
  given; `context=True` adds the dataset's `ctx_*` context columns, what `baseline("context")`
  learns from), NaN and inf (a rate over a zero duration) set to 0 as the benchmark does;
- `y`: the class of each flow (`label`, 'Benign' or an attack class);
- `groups`: the run of each flow (`run_id`), for grouped splits (`sklearn.model_selection.GroupKFold`
  or `uavcas.ids.splits.grouped_split`): flows of one run share its channel and timing;
- `meta`: every other column (ids, axes, per-family labels, counts, sequences), same index.
No metadata column is ever among the features.
"""

from __future__ import annotations

from collections.abc import Iterable
from pathlib import Path
from typing import NamedTuple

import pandas as pd

from .read import load_any


class Dataset(NamedTuple):
    X: pd.DataFrame
    y: pd.Series
    groups: pd.Series
    meta: pd.DataFrame


def load_dataset(path: str | Path, view: str | None = None, features: str | Iterable[str] | None = None,
                 fmt: str | None = None, context: bool = False) -> Dataset:
    """Read `path` (any format `uavcas.dataset.read.load_any` reads; `fmt` names it when the path
    does not tell) and split it into features, labels, groups and metadata.

    `view` picks one flow view when the dataset holds several; `features` is a feature-set name of
    the schema (e.g. 'cic', 'paper'), a list of feature columns, or None for the dataset's own;
    `context` appends the context columns (`schema.CONTEXT_FEATURES`; an error when the dataset
    has none).
    """
    from uavcas.ids.features import context_columns, context_matrix, finite_features, resolve_features

    df = load_any(path, fmt, view=view).reset_index(drop=True)
    if "label" not in df.columns:
        raise ValueError(f"{path}: no 'label' column")
    cols = resolve_features(df, features)
    if context:
        context_matrix(df.head(1))  # refuses a dataset without the columns
        cols = cols + [c for c in context_columns(df) if c not in cols]
    X = pd.DataFrame(finite_features(df, cols), columns=cols, index=df.index)
    groups = df["run_id"].astype(str).rename("run_id") if "run_id" in df.columns else pd.Series(
        df.index.astype(str), index=df.index, name="run_id")
    meta = df.drop(columns=cols)
    X.attrs.update(df.attrs)
    return Dataset(X, df["label"].astype(str).rename("label"), groups, meta)
