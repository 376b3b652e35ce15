"""Datasets for the benchmark and the analyses: ours (flows.parquet) or an external IDS sample.

External samples are read by the dataset package's loaders (`uavcas.dataset.external`), which
map them onto our feature names (NaN where a dataset has no counterpart). Here they are only
made comparable: benign rows ('BENIGN', 'Normal') become 'Benign', features absent from the
whole file are listed in `df.attrs["absent_features"]` (they are 0 for the models), and since
external data have no runs each row is its own group (`run_id` = row number): the grouped split
degenerates to a stratified flow-level split there, which the results state.
"""

from __future__ import annotations

from pathlib import Path

import pandas as pd

from uavcas.dataset import schema

FORMATS = ("uavcas", "cicids2017", "unsw-nb15")
_BENIGN_NAMES = {"BENIGN": schema.BENIGN, "Benign": schema.BENIGN, "benign": schema.BENIGN, "Normal": schema.BENIGN}


def detect_format(path: str | Path) -> str:
    """'uavcas' (flows.parquet or a .parquet file), 'cicids2017' or 'unsw-nb15' (CSV header)."""
    p = Path(path)
    if not p.exists():
        raise FileNotFoundError(f"{p} does not exist")
    if p.suffix == ".parquet" or (p / "flows.parquet").is_file():
        return "uavcas"
    csvs = sorted(p.glob("*.csv")) if p.is_dir() else ([p] if p.suffix == ".csv" else [])
    for f in csvs:
        with open(f, encoding="utf-8-sig", errors="replace") as fh:
            header = fh.readline()
        if "attack_cat" in header:
            return "unsw-nb15"
        if "Label" in header and "Flow" in header:
            return "cicids2017"
    raise ValueError(f"{p}: neither a uavcas dataset (flows.parquet) nor a CICIDS2017/UNSW-NB15 CSV sample")


def load_external(path: str | Path, fmt: str) -> pd.DataFrame:
    from uavcas.dataset.external import LOADERS

    if fmt not in LOADERS:
        raise ValueError(f"unknown external format {fmt!r} (known: {', '.join(LOADERS)})")
    df = LOADERS[fmt](path)
    df["label"] = df["label"].astype(str).str.strip().replace(_BENIGN_NAMES)
    df["run_id"] = [f"{fmt}-{i}" for i in range(len(df))]
    df.attrs["absent_features"] = [f for f in schema.FEATURES if f in df.columns and df[f].isna().all()]
    df.attrs["source"] = fmt
    return df


def load_any(path: str | Path, fmt: str | None = None, view: str | None = None) -> pd.DataFrame:
    """A uavcas dataset (one flow view) or an external sample, as a frame with our feature
    names and `label`."""
    from uavcas.analysis.io import load_flows, select_view

    fmt = fmt or detect_format(path)
    if fmt not in FORMATS:
        raise ValueError(f"unknown format {fmt!r} (known: {', '.join(FORMATS)})")
    if fmt != "uavcas":
        return load_external(path, fmt)
    return select_view(load_flows(path), view)
