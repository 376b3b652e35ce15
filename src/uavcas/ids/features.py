"""The feature matrix of a flow table: flow features and nothing else.

Metadata (run id, config, axes, addresses, labels, sequences: schema.METADATA_COLUMNS and every
column that is no flow feature) must never reach a model — the authors' `config_idx` among the
features is the defect this module exists to prevent.

Feature lists come from the feature-standard registry (`uavcas.flows.standards`: each standard's
columns) and the view registry (`uavcas.views`: a view whose rows are no flows, the window-host
view, has its own columns from flows of each standard, and its own context columns; a flow's are
`schema.CONTEXT_FEATURES`, observations of the switches around a flow), which only the models
that ask for them receive (`context_matrix`).
"""

from __future__ import annotations

from collections.abc import Iterable

import numpy as np
import pandas as pd

from uavcas.flows.standards import DEFAULT_STANDARD, names, standards
from uavcas.views import frame_view, views


class MetadataLeakError(ValueError):
    """A column that is not a flow feature was requested as a feature."""


def feature_sets() -> dict[str, tuple[str, ...]]:
    """Named feature sets: every registered standard's columns under its name ('cic', 'paper'),
    then those of each view whose rows have their own ('window-host-cic', 'window-host-paper':
    `ViewSpec.feature_set`)."""
    sets = {s.name: s.columns for s in standards()}
    for v in views():
        sets.update({v.feature_set(s.name): v.feature_columns(s.name) for s in standards()})
    return sets


def known_features() -> set[str]:
    return set().union(*feature_sets().values(), *(v.context_columns for v in views()))


def context_columns(df: pd.DataFrame) -> tuple[str, ...]:
    """The context columns of `df`'s kind of row (its view's, `uavcas.views.frame_view`): the
    flows' ctx_*, or their episode summaries."""
    return frame_view(df).context_columns


def check_feature_columns(columns: Iterable[str]) -> list[str]:
    """Return `columns` as a list if every one is a schema feature; raise otherwise."""
    cols = list(columns)
    known = known_features()
    meta = [c for c in cols if any(c in v.metadata_columns for v in views())]
    other = [c for c in cols if c not in known and c not in meta]
    if meta or other:
        raise MetadataLeakError(f"not flow features (never used by the IDS): {meta + other}")
    if not cols:
        raise MetadataLeakError("no feature column")
    return cols


def resolve_features(df: pd.DataFrame, spec: str | Iterable[str] | None = None) -> list[str]:
    """The feature columns to use on `df`.

    None: the dataset's feature set (rows of a view with its own columns: the view's set of their
    flows' standard, e.g. window-host-cic;
    `df.attrs['feature_standard']` when it names one, else the first set whose columns `df` all
    has, else the default standard's features `df` has); a name: that set, every
    column of which `df` must have; a list: those columns (checked to be features).
    """
    sets = feature_sets()
    if spec is None:
        named = df.attrs.get("feature_standard", df.attrs.get("features"))
        view = frame_view(df)
        if view.feature_set(DEFAULT_STANDARD) != DEFAULT_STANDARD:  # rows with the view's own columns
            named = view.feature_set(named if named in names() else DEFAULT_STANDARD)
        if isinstance(named, str) and named in sets:
            spec = named
        else:
            full = [n for n, cols in sets.items() if set(cols) <= set(df.columns)]
            if not full:
                return check_feature_columns([f for f in sets[DEFAULT_STANDARD] if f in df.columns])
            spec = full[0]
    if isinstance(spec, str):
        if spec not in sets:
            raise ValueError(f"unknown feature set {spec!r}; known: {', '.join(sets)}")
        cols = list(sets[spec])
    else:
        cols = check_feature_columns(spec)
    missing = [c for c in cols if c not in df.columns]
    if missing:
        raise ValueError(f"feature columns missing from the dataset: {missing}")
    return cols


def finite_features(df: pd.DataFrame, columns: list[str]) -> np.ndarray:
    """float64 values of `columns`; inf (a rate over a zero duration) and NaN become 0: the
    estimators need finite input and a zero rate is what CICFlowMeter writes for a one-packet flow."""
    return np.nan_to_num(df[columns].to_numpy(dtype=np.float64), nan=0.0, posinf=0.0, neginf=0.0)


def feature_matrix(df: pd.DataFrame, columns: Iterable[str] | str | None = None) -> np.ndarray:
    """float32 matrix of the features `columns` (see `resolve_features`) of `df`, finite."""
    x = finite_features(df, resolve_features(df, columns))
    # float32 overflows above 3.4e38; clip so huge rates stay finite
    return np.clip(x, -1e30, 1e30).astype(np.float32)


def context_matrix(df: pd.DataFrame) -> np.ndarray:
    """float32 matrix of the context columns (`context_columns`: the flows' `schema.CONTEXT_FEATURES`,
    or their episode summaries for window-host rows) of `df`."""
    cols = context_columns(df)
    missing = [c for c in cols if c not in df.columns]
    if missing:
        raise ValueError(f"the dataset has no context columns ({len(missing)} ctx_* missing): extract its runs "
                         "with this uavcas (`uavcas extract RUN_DIR --out DIR`) to add them")
    return feature_matrix(df, list(cols))
