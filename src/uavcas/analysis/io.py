"""The one place analysis/ids read a dataset, so it can later delegate to `uavcas.dataset`."""

from __future__ import annotations

from pathlib import Path

import pandas as pd


def flows_path(path: str | Path) -> Path:
    """`DATASET_DIR/flows.parquet` for a dataset directory, or the parquet file itself."""
    p = Path(path)
    if p.is_dir():
        p = p / "flows.parquet"
    if not p.is_file():
        raise FileNotFoundError(f"no flows table at {p} (expected a dataset directory or a .parquet file)")
    return p


def load_flows(path: str | Path, columns: list[str] | None = None) -> pd.DataFrame:
    """Read a dataset's flow table (all columns, or `columns`).

    Delegates to the dataset package's reader (list columns stay Arrow-backed); plain pandas
    if that reader is unavailable, so analysis does not depend on the writer's internals.
    """
    p = flows_path(path)
    try:
        from uavcas.dataset.parquet import read_flows
    except ImportError:  # pragma: no cover - the dataset package predates this fallback's removal
        return pd.read_parquet(p, columns=columns)
    return read_flows(p, columns=columns)


def select_view(df: pd.DataFrame, view: str | None = None) -> pd.DataFrame:
    """Rows of one flow view ('5tuple' or 'hostpair').

    A dataset whose runs were extracted with different views holds two descriptions of the same
    traffic; mixing them would count packets twice, so that needs an explicit choice.
    """
    if "view" not in df.columns:
        if view is not None:
            raise ValueError(f"--view {view}: this dataset has no 'view' column")
        return df
    views = sorted(df["view"].dropna().astype(str).unique())
    if view is None:
        if len(views) > 1:
            raise ValueError(f"the dataset mixes flow views {views}: choose one with --view")
        return df
    if view not in views:
        raise ValueError(f"--view {view}: not in this dataset (views: {views})")
    return df[df["view"].astype(str) == view].reset_index(drop=True)
