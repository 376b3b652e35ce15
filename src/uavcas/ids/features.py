"""The feature matrix of a flow table: the 47 schema features and nothing else.

Metadata (run id, config, axes, addresses, labels, sequences: schema.METADATA_COLUMNS and every
column not in schema.FEATURES) must never reach a model — the authors' `config_idx` among the
features is the defect this module exists to prevent.
"""

from __future__ import annotations

from collections.abc import Iterable

import numpy as np
import pandas as pd

from uavcas import schema


class MetadataLeakError(ValueError):
    """A column that is not one of the 47 flow features was requested as a feature."""


def check_feature_columns(columns: Iterable[str]) -> list[str]:
    """Return `columns` as a list if every one is a schema feature; raise otherwise."""
    cols = list(columns)
    meta = [c for c in cols if c in schema.METADATA_COLUMNS]
    known = set(schema.FEATURES) | set(schema.PAPER_FEATURES)  # either feature standard
    other = [c for c in cols if c not in known and c not in meta]
    if meta or other:
        raise MetadataLeakError(
            f"not flow features (never used by the IDS): {meta + other}"
        )
    if not cols:
        raise MetadataLeakError("no feature column")
    return cols


def feature_matrix(df: pd.DataFrame, columns: Iterable[str] | None = None) -> np.ndarray:
    """float32 matrix of the schema features present in `df` (or of `columns`, checked).

    inf (a rate over a zero duration) and NaN become 0: the estimators need finite input and a
    zero rate is what CICFlowMeter writes for a one-packet flow.
    """
    standard = schema.feature_columns(df.attrs.get("feature_standard", schema.DEFAULT_STANDARD))
    cols = check_feature_columns(columns if columns is not None else [f for f in standard if f in df.columns])
    missing = [c for c in cols if c not in df.columns]
    if missing:
        raise ValueError(f"feature columns missing from the dataset: {missing}")
    x = df[cols].to_numpy(dtype=np.float64)
    x = np.nan_to_num(x, nan=0.0, posinf=0.0, neginf=0.0)
    # float32 overflows above 3.4e38; clip so huge rates stay finite
    return np.clip(x, -1e30, 1e30).astype(np.float32)
