"""The authors' CSV layout ("uavcas-csv"): per run a `<name>_ts.csv` and a `<name>_stat.csv`.

The published UAV-CAS files could not be inspected, so the layout is defined from the paper
(tshark per-packet fields aggregated into flows, sequences of (timestamp, size, flags) tuples):

`<name>_ts.csv`, one row per flow, per-packet sequences as Python list literals:
    flow_id, src_ip, src_port, dst_ip, dst_port, protocol, config, label,
    timestamps  "[1700000001.000050, 1700000001.010050, ...]"  (absolute frame.time_epoch, s)
    sizes       "[74, 74, 66, ...]"                            (frame.len, bytes)
    flags       "[2, 18, 16, ...]"                             (TCP flags as integers)
    directions  "[1, -1, 1, ...]"                              (+1 forward, -1 backward)
`<name>_stat.csv`, one row per flow: flow_id, src_ip, src_port, dst_ip, dst_port, protocol,
    config, the 47 features (schema.FEATURES names, our units), label.

Reading accepts these names and a few aliases (`ts`/`time`/`frame.time_epoch`,
`size`/`lengths`/`frame.len`, `tcp.flags`, `dirs`/`direction`); flag values may be written as
hex strings ('0x0012') as tshark prints them. Reading returns our schema's column names with
sequences as Arrow list columns and `label_<family>` derived from the class string.
"""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pandas as pd
import pyarrow as pa

from uavcas.atomic import atomic_path

from uavcas.schema import FAMILIES, FAMILY_CLASS, FEATURES

ID_COLS = ("flow_id", "src_ip", "src_port", "dst_ip", "dst_port", "protocol", "config")
TS_ALIASES = {
    "timestamps": ("timestamps", "ts", "time", "times", "frame.time_epoch"),
    "sizes": ("sizes", "size", "lengths", "frame.len"),
    "flags": ("flags", "tcp.flags"),
    "directions": ("directions", "dirs", "direction"),
}


class CsvFormatError(ValueError):
    """A uavcas-csv file that cannot be read; names the file and column."""


def _list_literals(values: np.ndarray, starts: np.ndarray, fmt: str) -> list[str]:
    text = np.char.mod(fmt, values).tolist() if values.shape[0] else []
    return ["[" + ", ".join(text[a:b]) + "]" for a, b in zip(starts[:-1].tolist(), starts[1:].tolist())]


def _offsets(col: pd.Series) -> tuple[np.ndarray, np.ndarray]:
    arr = pa.array(col.array) if isinstance(col.dtype, pd.ArrowDtype) else pa.array(col.tolist())
    if isinstance(arr, pa.ChunkedArray):
        arr = arr.combine_chunks()
    return arr.offsets.to_numpy().astype(np.int64), arr.flatten().to_numpy(zero_copy_only=False)


def write_uavcas_csv(df: pd.DataFrame, out_dir: Path, name: str) -> tuple[Path, Path]:
    """Write one `<name>_ts.csv` and `<name>_stat.csv` pair from flows in our schema."""
    out_dir.mkdir(parents=True, exist_ok=True)
    ident = pd.DataFrame({c: df[c].to_numpy() for c in ID_COLS})
    starts, rel = _offsets(df["seq_time_s"])
    first = np.repeat(df["first_ts"].to_numpy(), np.diff(starts))
    ts = ident.copy()
    ts["label"] = df["label"].to_numpy()
    ts["timestamps"] = _list_literals(first + rel, starts, "%.6f")
    for col, key in (("seq_size", "sizes"), ("seq_flags", "flags"), ("seq_dir", "directions")):
        s, v = _offsets(df[col])
        ts[key] = _list_literals(v.astype(np.int64), s, "%d")
    stat = pd.concat([ident, df[list(FEATURES)].reset_index(drop=True)], axis=1)
    stat["label"] = df["label"].to_numpy()
    paths = (out_dir / f"{name}_ts.csv", out_dir / f"{name}_stat.csv")
    for frame, path in zip((ts, stat), paths):
        with atomic_path(path) as tmp:
            frame.to_csv(tmp, index=False)
    return paths


_NUM = re.compile(r"[\[\]\s'\"]")


def _parse_lists(col: pd.Series, path: Path, name: str, dtype, hex_ok: bool = False) -> pd.arrays.ArrowExtensionArray:
    """Column of list literals -> Arrow list column, parsed with one split over all rows."""
    bodies = [_NUM.sub("", str(s)) for s in col.tolist()]
    lengths = np.array([0 if not b else b.count(",") + 1 for b in bodies], dtype=np.int64)
    joined = ",".join(b for b in bodies if b)
    tokens = joined.split(",") if joined else []
    try:
        if hex_ok and any(t.startswith("0x") for t in tokens[:10]):
            values = np.array([int(t, 16) for t in tokens], dtype=dtype)
        else:
            values = np.array(tokens, dtype=np.float64).astype(dtype)
    except ValueError as exc:
        raise CsvFormatError(f"{path}: column '{name}' holds a value that is not a number ({exc})") from None
    starts = np.concatenate(([0], np.cumsum(lengths))).astype(np.int32)
    return pd.arrays.ArrowExtensionArray(pa.ListArray.from_arrays(pa.array(starts), pa.array(values)))


def _pick(df: pd.DataFrame, key: str, path: Path) -> str:
    for alias in TS_ALIASES[key]:
        if alias in df.columns:
            return alias
    raise CsvFormatError(f"{path}: no '{key}' column (accepted: {', '.join(TS_ALIASES[key])})")


def _families_from_label(labels: pd.Series) -> dict[str, np.ndarray]:
    parts = labels.fillna("Benign").astype(str).str.split("+")
    return {f: parts.map(lambda p, c=FAMILY_CLASS[f]: c in p).to_numpy(bool) for f in FAMILIES}


def read_uavcas_csv(ts_path: Path, stat_path: Path | None = None) -> pd.DataFrame:
    """Read a `_ts.csv` (and its `_stat.csv`, found beside it by default) into our columns."""
    ts_path = Path(ts_path)
    if stat_path is None:
        cand = ts_path.with_name(ts_path.name.replace("_ts.csv", "_stat.csv"))
        stat_path = cand if cand.exists() and cand != ts_path else None
    try:
        ts = pd.read_csv(ts_path)
    except (OSError, pd.errors.ParserError, UnicodeDecodeError) as exc:
        raise CsvFormatError(f"{ts_path}: cannot read CSV ({str(exc).splitlines()[0]})") from None
    cols = {k: _pick(ts, k, ts_path) for k in ("timestamps", "sizes", "flags")}
    out = ts[[c for c in ID_COLS + ("label",) if c in ts.columns]].copy()
    abs_t = _parse_lists(ts[cols["timestamps"]], ts_path, cols["timestamps"], np.float64)
    a = pa.array(abs_t)
    firsts = _first_elements(a)
    out["first_ts"] = firsts
    rel = a.flatten().to_numpy() - np.repeat(firsts, np.diff(a.offsets.to_numpy()))
    out["seq_time_s"] = pd.arrays.ArrowExtensionArray(pa.ListArray.from_arrays(a.offsets, pa.array(rel)))
    out["seq_size"] = _parse_lists(ts[cols["sizes"]], ts_path, cols["sizes"], np.int32)
    out["seq_flags"] = _parse_lists(ts[cols["flags"]], ts_path, cols["flags"], np.int16, hex_ok=True)
    dcol = next((c for c in TS_ALIASES["directions"] if c in ts.columns), None)
    if dcol is not None:
        out["seq_dir"] = _parse_lists(ts[dcol], ts_path, dcol, np.int8)
    if stat_path is not None:
        stat = pd.read_csv(stat_path)
        if len(stat) != len(ts):
            raise CsvFormatError(f"{stat_path}: {len(stat)} rows, but {ts_path} has {len(ts)}")
        for f in FEATURES:
            if f in stat.columns:
                out[f] = stat[f].to_numpy(np.float64)
    if "label" in out.columns:
        for fam, hit in _families_from_label(out["label"]).items():
            out[f"label_{fam}"] = hit
    return out


def _first_elements(a: pa.ListArray) -> np.ndarray:
    """First element of each list (NaN for an empty list)."""
    off = a.offsets.to_numpy()
    vals = a.flatten().to_numpy()
    out = np.full(len(a), np.nan)
    nonempty = np.diff(off) > 0
    out[nonempty] = vals[off[:-1][nonempty]]
    return out
