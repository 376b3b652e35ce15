"""The one reader of flow datasets, whatever their format, for the analyses and the benchmark.

Formats (`FORMATS`), each parsed by its own module of this package:
- 'uavcas': our dataset directory (flows.parquet) or a .parquet file (`parquet.read_flows`);
- 'uavcas-csv': the authors' released layout, `UAV-CAS_stat.csv` + `UAV-CAS_ts.csv` (or the `_cfg`
  variants) in a directory, or one of the files (`uavcas_csv.read_layout`); its features are the
  `paper` standard (`df.attrs["feature_standard"]`);
- 'cicids2017', 'unsw-nb15': external CSV samples (`external.LOADERS`).

Every frame comes back with our feature names and `label`, benign rows named 'Benign'. External
samples have no runs, so each row is its own group (`run_id` = row number): the grouped split
degenerates to a stratified flow-level split there, which the results state. Features absent
from the whole file are listed in `df.attrs["absent_features"]` (the models see them as 0).
"""

from __future__ import annotations

from pathlib import Path

import pandas as pd

from uavcas.flows.standards import DEFAULT_STANDARD, feature_columns
from uavcas.schema import BENIGN

from .external import LOADERS
from .parquet import read_flows
from .uavcas_csv import STAT_CFG_FILE, STAT_FILE, TS_CFG_FILE, TS_FILE, read_layout

FORMATS = ("uavcas", "uavcas-csv", "cicids2017", "unsw-nb15")  # what `read_any` reads
# what `uavcas export` writes: the authors' layout (`uavcas_csv`), or one CSV row per flow with
# CICIDS2017's names (`cic_csv`)
EXPORT_FORMATS = ("uavcas-csv", "csv")
IMPORT_FORMATS = ("uavcas-csv",)  # what `uavcas import` reads back into a dataset directory
_BENIGN_NAMES = {"BENIGN": BENIGN, "Benign": BENIGN, "benign": BENIGN, "Normal": BENIGN}
_LAYOUT_FILES = (STAT_FILE, TS_FILE, STAT_CFG_FILE, TS_CFG_FILE)


def flows_path(path: str | Path) -> Path:
    """`DATASET_DIR/flows.parquet` for a dataset directory, or the parquet file itself."""
    p = Path(path)
    if p.is_dir():
        p = p / "flows.parquet"
    if not p.is_file():
        raise FileNotFoundError(f"no flows table at {p} (expected a dataset directory or a .parquet file)")
    return p


def detect_format(path: str | Path) -> str:
    """One of `FORMATS`, from the file name or the CSV header; ValueError if none fits."""
    p = Path(path)
    if not p.exists():
        raise FileNotFoundError(f"{p} does not exist")
    if p.suffix == ".parquet" or (p / "flows.parquet").is_file():
        return "uavcas"
    if (p.is_dir() and any((p / f).is_file() for f in _LAYOUT_FILES)) or p.name in _LAYOUT_FILES:
        return "uavcas-csv"
    csvs = sorted(p.glob("*.csv")) if p.is_dir() else ([p] if p.suffix == ".csv" else [])
    for f in csvs:
        with open(f, encoding="utf-8-sig", errors="replace") as fh:
            header = fh.readline()
        names = {c.strip() for c in header.split(",")}
        if {"packet_time", "packet_size"} <= names or {"config_idx", "Total Packets"} <= names:
            return "uavcas-csv"
        if "attack_cat" in header:
            return "unsw-nb15"
        if "Label" in header and "Flow" in header:
            return "cicids2017"
    raise ValueError(
        f"{p}: neither a uavcas dataset (flows.parquet), the authors' CSV ({STAT_FILE}/{TS_FILE}) "
        "nor a CICIDS2017/UNSW-NB15 CSV sample"
    )


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


def _read_external(path: Path, fmt: str) -> pd.DataFrame:
    df = LOADERS[fmt](path)
    df["run_id"] = [f"{fmt}-{i}" for i in range(len(df))]
    return df


def load_any(path: str | Path, fmt: str | None = None, view: str | None = None) -> pd.DataFrame:
    """The flows at `path` in format `fmt` (detected when None), one flow view, with our feature
    names, `label` (benign as 'Benign') and `run_id`; `attrs` name the source and absent features."""
    p = Path(path)
    fmt = fmt or detect_format(p)
    if fmt not in FORMATS:
        raise ValueError(f"unknown format {fmt!r} (known: {', '.join(FORMATS)})")
    if fmt == "uavcas":
        df = read_flows(flows_path(p))
    elif fmt == "uavcas-csv":
        imp = read_layout(p)
        df = imp.frame
        df.attrs["lacks"] = imp.lacks
    else:
        df = _read_external(p, fmt)
    attrs = dict(df.attrs)
    df = select_view(df, view)
    df.attrs.update(attrs)
    standard = df.attrs.setdefault("feature_standard", DEFAULT_STANDARD)
    if fmt != "uavcas":
        df["label"] = df["label"].astype(str).str.strip().replace(_BENIGN_NAMES)
        df.attrs["absent_features"] = [f for f in feature_columns(standard)
                                       if f not in df.columns or df[f].isna().all()]
    df.attrs["source"] = fmt
    return df
