"""The authors' released layout ("uavcas-csv"), both ways: ONE `UAV-CAS_stat.csv`, ONE `UAV-CAS_ts.csv`.

As their generators write them (Sripathm2/Collaborative-UAV-Dataset, `Scripts/6-build_stat_csv.py`
and `Scripts/3-build_ts_csv.py`; Python `csv.writer`, QUOTE_MINIMAL, CRLF line ends):

`UAV-CAS_stat.csv` (`STAT_COLUMNS`, 59): `config_idx, num_drones, num_bs, payload, pathloss,
modulation, mission, tx_power, noise, src_ip, dst_ip`, the 47 `paper` features
(`uavcas.flows.standards.paper`; integer ones written as integers), `Label`; one
row per flow of at least `STAT_MIN_PACKETS` (10) packets. `src_ip` is the string-smaller address.
`UAV-CAS_ts.csv` (`TS_COLUMNS`): `packet_time, packet_size, [packet_flag,] packet_dir, Label`,
one row per flow of at least `TS_MIN_PACKETS` (2) packets, each list a Python literal: times as
`repr(float)` Unix seconds, sizes (frame bytes), flags as tshark prints them (`'0x0012'`, `''`
for a packet without TCP), direction 0 when the sender is the string-smaller address.
`--embed-config` writes the `_cfg` variants, whose Label is `<class>|<config string>`.

Both files list flows in the same order (the dataset's), so the stat rows are exactly the ts rows
of >= 10 packets, in order: that is how `read_layout` joins them.

Export maps our dataset onto the layout: `config_idx` = the run id when it is an integer (a
campaign's manifest index), else the run's rank; the meta strings come from the axis columns
(`noise` is the noise floor's magnitude, '95' for -95 dBm); features are the dataset's own when
its standard is `paper`, else computed from the packet sequences with the authors' definitions.
Import reads theirs (as released) or ours into a `paper`-standard frame, keeping what the layout
carries; it lacks ports, protocol, seeds, capture points, run ids of flows under 10 packets (their
rows carry no `config_idx`), and, without `packet_flag`, the per-packet TCP flags.
"""

from __future__ import annotations

import csv
import re
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pandas as pd
import pyarrow as pa
import pyarrow.compute as pc

from uavcas.atomic import atomic_path, ensure_out_dir
from uavcas.flows.packets import ns_to_s
from uavcas.flows.standards.paper import INT_FEATURES, PAPER_FEATURES, paper_features
from uavcas.flows.standards.paper import STANDARD as PAPER
from uavcas.schema import FAMILIES, FAMILY_CLASS, TRUTH_COLUMNS
from uavcas.views import frame_view

STAT_FILE, TS_FILE = "UAV-CAS_stat.csv", "UAV-CAS_ts.csv"
STAT_CFG_FILE, TS_CFG_FILE = "UAV-CAS_stat_cfg.csv", "UAV-CAS_ts_cfg.csv"
META_COLUMNS: tuple[str, ...] = (
    "config_idx", "num_drones", "num_bs", "payload", "pathloss", "modulation", "mission", "tx_power", "noise",
    "src_ip", "dst_ip",
)  # fmt: skip
STAT_COLUMNS: tuple[str, ...] = META_COLUMNS + PAPER_FEATURES + ("Label",)
TS_COLUMNS: tuple[str, ...] = ("packet_time", "packet_size", "packet_dir", "Label")
TS_FLAG_COLUMNS: tuple[str, ...] = ("packet_time", "packet_size", "packet_flag", "packet_dir", "Label")
STAT_MIN_PACKETS, TS_MIN_PACKETS = 10, 2
NO_FLAGS = -1  # seq_flags value of a packet whose flag field was empty (not TCP)
NS = 1_000_000_000
IMPORT_LACKS = ("src_port", "dst_port", "protocol", "seed", "capture_point",
                "per-packet effects (seq_effect, attack_packets)")
assert len(STAT_COLUMNS) == 59


class CsvFormatError(ValueError):
    """A uavcas-csv file that cannot be read or written; names the file and what is wrong."""


# ------------------------------------------------------------------------------------ export


@dataclass
class Written:
    stat: Path
    ts: Path
    n_stat: int
    n_ts: int
    notes: list[str] = field(default_factory=list)


def _lists(col: pd.Series) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(values, lengths, null) of a list column, whatever its chunking or slicing."""
    arr = pa.array(col.array) if isinstance(col.dtype, pd.ArrowDtype) else pa.array(col.tolist())
    chunks = arr.chunks if isinstance(arr, pa.ChunkedArray) else [arr]
    vals, lens, nulls = [], [], []
    for ch in chunks:
        # flatten() honours a sliced array's offset; raw .offsets would not (the old export bug)
        vals.append(ch.flatten().to_numpy(zero_copy_only=False))
        lens.append(pc.fill_null(pc.list_value_length(ch), 0).to_numpy(zero_copy_only=False))
        nulls.append(ch.is_null().to_numpy(zero_copy_only=False))
    return (np.concatenate(vals) if vals else np.zeros(0), np.concatenate(lens).astype(np.int64),
            np.concatenate(nulls).astype(bool))  # fmt: skip


def _meta_strings(df: pd.DataFrame) -> dict[str, list[str]]:
    """num_drones .. noise as the authors' config parts, from the axis columns."""

    def num(v) -> str:
        if v is None or (isinstance(v, float) and np.isnan(v)):
            return ""
        f = float(v)
        return str(int(f)) if f.is_integer() else repr(f)

    out = {
        "num_drones": [num(v) for v in df["n_uav"]],
        "num_bs": [num(v) for v in df["n_bs"]],
        "tx_power": [num(v) for v in df["tx_dbm"]],
        "noise": [num(-v) if v is not None and not pd.isna(v) else "" for v in df["noise_dbm"]],
    }
    for ours, theirs in (("payload", "payload"), ("pathloss", "pathloss"), ("modulation", "modulation"),
                         ("mission", "mission")):
        out[theirs] = ["" if pd.isna(v) else str(v) for v in df[ours]]
    return out


def _config_idx(run_ids: pd.Series) -> list[int]:
    order: dict[str, int] = {}
    for r in run_ids.astype(str):
        order.setdefault(r, len(order))
    return [int(r) if r.isdigit() else order[r] for r in run_ids.astype(str)]


def _fmt_feature(name: str, v: float) -> str:
    return str(int(v)) if name in INT_FEATURES else repr(float(v))


HOST_PAIR_VIEWS = ("hostpair", "window-hostpair")


def host_pair_rows(df: pd.DataFrame) -> pd.DataFrame:
    """5-tuple flows -> one row per (run, unordered address pair), from their packet sequences.

    The authors' rows are host pairs; a flood's 5-tuple flows have 1-5 packets each, so exported
    as they are they fall under the layout's 10-packet minimum and the DoS class vanishes. The
    sequences (`seq_*`) hold every packet of every flow, so the pair's packets are their union,
    ordered by time: direction +1 = sent by the string-smaller address (the row's src_ip),
    flags of non-TCP packets empty, label = the union of its flows' families. Each 5-tuple flow
    keeps its own capture point (the host-pair view picks one per pair), so a pair's packets may
    come from several switches, microseconds apart; features are recomputed from the merged
    sequences with the authors' definitions."""
    if df.empty:
        return df
    t_rel, lens, null = _lists(df["seq_time_s"])
    if null.any():
        raise CsvFormatError("the dataset's 5-tuple flows lack packet sequences (seq_*); extract its runs with "
                             "`uavcas extract RUN --view hostpair` to export host pairs")
    sizes, _, _ = _lists(df["seq_size"])
    dirs, _, _ = _lists(df["seq_dir"])
    flags, _, _ = _lists(df["seq_flags"])
    src, dst = df["src_ip"].astype(str).to_numpy(), df["dst_ip"].astype(str).to_numpy()
    src_small = src <= dst
    small, large = np.where(src_small, src, dst), np.where(src_small, dst, src)
    pair = pd.DataFrame({"r": df["run_id"].astype(str).to_numpy(), "a": small, "b": large}).groupby(
        ["r", "a", "b"], sort=False).ngroup().to_numpy(np.int64)
    n = int(pair.max()) + 1
    g = np.repeat(np.arange(len(df)), lens)
    abs_ns = df["first_ts_ns"].to_numpy(np.int64)[g] + np.round(t_rel.astype(np.float64) * 1e9).astype(np.int64)
    order = np.lexsort((np.arange(g.shape[0]), abs_ns, pair[g]))
    gp, ns = pair[g][order], abs_ns[order]
    tcp = df["protocol"].to_numpy(dtype=np.float64, na_value=np.nan) == 6
    new_dir = np.where((dirs.astype(np.int64) == 1) == src_small[g], 1, -1).astype(np.int8)[order]
    new_flags = np.where(tcp[g], flags.astype(np.int64), NO_FLAGS).astype(np.int16)[order]
    plen = np.bincount(gp, minlength=n).astype(np.int64)
    starts = np.concatenate(([0], np.cumsum(plen))).astype(np.int64)
    first_ns, last_ns = ns[starts[:-1]], ns[starts[1:] - 1]
    head = np.unique(pair, return_index=True)[1]  # each pair's first flow (dataset order)
    out = df.iloc[head].reset_index(drop=True).copy()
    out["src_ip"], out["dst_ip"] = small[head], large[head]
    out["src_port"] = out["dst_port"] = out["protocol"] = pd.NA
    out["flow_id"] = np.arange(n, dtype=np.int64)
    out["view"] = "hostpair"
    out["first_ts_ns"], out["first_ts"], out["last_ts"] = first_ns, ns_to_s(first_ns), ns_to_s(last_ns)
    out["packets"] = plen
    out["bytes"] = np.bincount(gp, weights=sizes.astype(np.float64)[order], minlength=n).astype(np.int64)
    out["duration_s"] = (last_ns - first_ns) / 1e9
    for c, v, t in (("seq_time_s", (ns - first_ns[gp]) / 1e9, pa.float64()),
                    ("seq_size", sizes[order].astype(np.int32), pa.int32()),
                    ("seq_flags", new_flags, pa.int16()), ("seq_dir", new_dir, pa.int8())):  # fmt: skip
        out[c] = pd.arrays.ArrowExtensionArray(pa.ListArray.from_arrays(pa.array(starts.astype(np.int32)),
                                                                        pa.array(v, type=t)))
    fams = []
    for f in FAMILIES:
        hit = np.bincount(pair, weights=df[f"label_{f}"].to_numpy(dtype=bool).astype(np.float64), minlength=n) > 0
        out[f"label_{f}"] = hit
        fams.append(hit)
    out["label"] = ["+".join(FAMILY_CLASS[f] for f, h in zip(FAMILIES, hs) if h) or "Benign" for hs in zip(*fams)]
    return out


def layout_rows(df: pd.DataFrame) -> tuple[pd.DataFrame, list[str]]:
    """The rows to export, at the authors' granularity (host pairs), and what was done to get them.

    Host-pair views go as they are; 5-tuple flows are merged into host pairs (`host_pair_rows`);
    episodes (window-host) are no flows and have no sequences: refused."""
    views = set(df["view"].dropna().astype(str)) if "view" in df.columns else set()
    if views <= set(HOST_PAIR_VIEWS):  # host pairs, or rows of an import (no view)
        return df, []
    if views == {"5tuple"}:
        merged = host_pair_rows(df)
        merged.attrs["feature_standard"] = None  # the flows' features do not describe a pair: recomputed
        return merged, [f"{len(df)} 5-tuple flows merged into {len(merged)} host pairs (the authors' rows), from their "
                        "packet sequences; each 5-tuple kept its own capture point"]
    raise CsvFormatError(f"the uavcas-csv layout holds host-pair flows, not {', '.join(sorted(views))} rows; extract "
                         "with `uavcas extract RUN --view hostpair` (or `uavcas campaign run --view hostpair`)")


def write_layout(df: pd.DataFrame, out_dir: Path, embed_config: bool = False, include_flags: bool = False) -> Written:
    """Write `df` (flows with sequences, one view) as the authors' stat and ts CSVs in `out_dir`,
    row for row: the ts rows are the flows of >= 2 packets and the stat rows the ts rows of >= 10,
    in the same order. `uavcas export` first brings the rows to host pairs (`layout_rows`)."""
    spec = frame_view(df)
    if not spec.is_flow:
        raise CsvFormatError(f"{spec.name} rows ({spec.row.plural}) have no packet sequences: the layout holds "
                             "host-pair flows")
    out_dir = ensure_out_dir(out_dir)
    df = df.reset_index(drop=True)
    n = len(df)
    if embed_config and df["config"].isna().any():
        raise CsvFormatError("--embed-config: some flows have no config string (imported without one)")
    labels = df["label"].astype(str).tolist()
    if embed_config:
        labels = [f"{lab}|{cfg}" for lab, cfg in zip(labels, df["config"].astype(str))]
    src = df["src_ip"].tolist()
    dst = df["dst_ip"].tolist()
    # the string-smaller address sends direction 0; unknown addresses (imported ts rows) keep ours
    smaller = np.array([s is None or d is None or (not isinstance(s, str)) or s <= d for s, d in zip(src, dst)],
                       dtype=bool)

    t_rel, lens, no_seq = _lists(df["seq_time_s"])
    sizes, _, _ = _lists(df["seq_size"])
    dirs, _, _ = _lists(df["seq_dir"])
    flags, _, no_flags = _lists(df["seq_flags"])
    starts = np.concatenate(([0], np.cumsum(lens))).astype(np.int64)
    g = np.repeat(np.arange(n), lens)
    exact = df["first_ts_ns"]
    first_ts = df["first_ts"].to_numpy(dtype=np.float64, na_value=np.nan)
    fallback = np.round(np.nan_to_num(first_ts) * 1e9).astype(np.int64)
    first_ns = np.where(exact.isna().to_numpy(), fallback, exact.fillna(0).to_numpy(dtype=np.int64))
    abs_ns = first_ns[g] + np.round(t_rel.astype(np.float64) * 1e9).astype(np.int64)
    dir0 = (dirs.astype(np.int64) == 1) == smaller[g]
    if include_flags and no_flags[lens > 0].any():
        raise CsvFormatError("--include-flags: some flows have no per-packet flags (imported without packet_flag)")

    ts_rows = np.flatnonzero(~no_seq & (lens >= TS_MIN_PACKETS))
    ts_path = out_dir / (TS_CFG_FILE if embed_config else TS_FILE)
    proto = df["protocol"].to_numpy(dtype=np.float64, na_value=np.nan)
    with atomic_path(ts_path) as tmp, open(tmp, "w", newline="") as fh:
        w = csv.writer(fh, quoting=csv.QUOTE_MINIMAL)
        w.writerow(TS_FLAG_COLUMNS if include_flags else TS_COLUMNS)
        ns_list, size_list, dir_list, flag_list = abs_ns.tolist(), sizes.tolist(), dir0.tolist(), flags.tolist()
        for i in ts_rows.tolist():
            a, b = int(starts[i]), int(starts[i + 1])
            row = ["[" + ", ".join(repr(v / NS) for v in ns_list[a:b]) + "]",
                   "[" + ", ".join(str(int(v)) for v in size_list[a:b]) + "]"]  # fmt: skip
            if include_flags:
                tcp = proto[i] == 6 or np.isnan(proto[i])
                row.append("[" + ", ".join(repr("" if (v == NO_FLAGS or not tcp) else f"0x{int(v):04x}")
                                           for v in flag_list[a:b]) + "]")
            row.append("[" + ", ".join("0" if d else "1" for d in dir_list[a:b]) + "]")
            row.append(labels[i])
            w.writerow(row)

    if df.attrs.get("feature_standard") == PAPER.name:
        feats = {f: df[f].to_numpy(dtype=np.float64, na_value=np.nan) for f in PAPER_FEATURES}
        has = ~np.isnan(feats["Total Packets"])
    else:
        fl = np.where(flags.astype(np.int64) == NO_FLAGS, 0, flags.astype(np.int64))
        feats = paper_features(g, dir0, ns_to_s(abs_ns), sizes, fl, starts)
        has = ~no_seq
    packets = df["packets"].to_numpy(dtype=np.float64, na_value=np.nan)
    stat_rows = np.flatnonzero(has & (packets >= STAT_MIN_PACKETS))
    meta = _meta_strings(df)
    cidx = _config_idx(df["run_id"])
    stat_path = out_dir / (STAT_CFG_FILE if embed_config else STAT_FILE)
    with atomic_path(stat_path) as tmp, open(tmp, "w", newline="") as fh:
        w = csv.writer(fh, quoting=csv.QUOTE_MINIMAL)
        w.writerow(STAT_COLUMNS)
        for i in stat_rows.tolist():
            a, b = (src[i], dst[i]) if smaller[i] else (dst[i], src[i])
            row = [cidx[i], *(meta[k][i] for k in META_COLUMNS[1:9]), a, b]
            row += [_fmt_feature(f, feats[f][i]) for f in PAPER_FEATURES]
            row.append(labels[i])
            w.writerow(row)
    notes = []
    if len(ts_rows) < n:
        notes.append(f"{n - len(ts_rows)} flows under {TS_MIN_PACKETS} packets are not in {ts_path.name} (the layout's "
                     "minimum)")
    return Written(stat_path, ts_path, len(stat_rows), len(ts_rows), notes)


# ------------------------------------------------------------------------------------ import

_STRIP = re.compile(r"[\[\]\s'\"]")


def _split_lists(col: pd.Series, path: Path, name: str) -> tuple[list[str], np.ndarray]:
    """Column of list literals -> (tokens, lengths), with one split over all rows."""
    bodies = [_STRIP.sub("", str(s)) if not pd.isna(s) else "" for s in col.tolist()]
    lengths = np.array([0 if not b else b.count(",") + 1 for b in bodies], dtype=np.int64)
    joined = ",".join(b for b in bodies if b)
    return (joined.split(",") if joined else []), lengths


def _int_tokens(tokens: list[str], path: Path, name: str) -> np.ndarray:
    try:
        return np.array(tokens, dtype=np.float64).astype(np.int64)
    except ValueError as exc:
        raise CsvFormatError(f"{path}: column '{name}' holds a value that is not a number ({exc})") from None


def _time_tokens_ns(tokens: list[str], path: Path) -> np.ndarray:
    """Decimal seconds -> exact integer ns (float() would round to 238 ns at today's epoch)."""
    out = np.empty(len(tokens), dtype=np.int64)
    try:
        for k, t in enumerate(tokens):
            if "e" in t or "E" in t:
                out[k] = round(float(t) * NS)
                continue
            whole, _, frac = t.partition(".")
            neg = whole.startswith("-")
            v = int(whole or "0") * NS + (-1 if neg else 1) * int((frac + "000000000")[:9])
            out[k] = v
    except ValueError as exc:
        raise CsvFormatError(f"{path}: column 'packet_time' holds a value that is not a number ({exc})") from None
    return out


def _flag_tokens(tokens: list[str]) -> np.ndarray:
    return np.array([NO_FLAGS if not t else int(t, 16) if t.lower().startswith("0x") else int(t) for t in tokens],
                    dtype=np.int16)


def _list_array(values: np.ndarray, lengths: np.ndarray, pa_type, null: np.ndarray | None = None):
    offsets = pa.array(np.concatenate(([0], np.cumsum(lengths))).astype(np.int32))
    mask = pa.array(null) if null is not None and null.any() else None
    arr = pa.ListArray.from_arrays(offsets, pa.array(values, type=pa_type), mask=mask)
    return pd.arrays.ArrowExtensionArray(arr)


def _read_csv(path: Path) -> pd.DataFrame:
    """Every cell as text: numbers are converted by Python's float(), which is correctly rounded,
    so a value written with repr() reads back to the same double (the round trip is exact)."""
    try:
        return pd.read_csv(path, dtype=str, keep_default_na=False)
    except (OSError, pd.errors.ParserError, UnicodeDecodeError, ValueError) as exc:
        raise CsvFormatError(f"{path}: cannot read CSV ({str(exc).splitlines()[0]})") from None


def find_layout(path: Path) -> tuple[Path | None, Path | None]:
    """(stat, ts) files of the layout at `path`: a directory holding them, or one of the files."""
    path = Path(path)
    if path.is_file():
        if "_ts" in path.stem:
            return None, path
        return path, None
    if not path.is_dir():
        raise CsvFormatError(f"{path}: no such file or directory")
    stat = next((path / f for f in (STAT_FILE, STAT_CFG_FILE) if (path / f).is_file()), None)
    ts = next((path / f for f in (TS_FILE, TS_CFG_FILE) if (path / f).is_file()), None)
    if stat is None and ts is None:
        raise CsvFormatError(f"{path}: neither {STAT_FILE} nor {TS_FILE} (nor their _cfg variants)")
    if stat is not None and ts is not None and stat.name.endswith("_cfg.csv") != ts.name.endswith("_cfg.csv"):
        raise CsvFormatError(f"{path}: {stat.name} and {ts.name} are different variants")
    return stat, ts


@dataclass
class Imported:
    frame: pd.DataFrame  # our schema's columns, paper features
    lacks: list[str]
    notes: list[str]
    files: list[str]
    standard: str = PAPER.name  # the feature standard of `frame`: the layout's columns are the paper's


def _families(labels: pd.Series) -> dict[str, np.ndarray]:
    parts = labels.fillna("Benign").astype(str).str.split("+")
    return {f: parts.map(lambda p, c=FAMILY_CLASS[f]: c in p).to_numpy(bool) for f in FAMILIES}


def read_layout(path: Path) -> Imported:
    """The authors' stat/ts CSVs (theirs or ours) as a `paper`-standard flow frame (dataset order)."""
    stat_path, ts_path = find_layout(Path(path))
    notes: list[str] = []
    lacks = list(IMPORT_LACKS)
    stat = None
    if stat_path is not None:
        stat = _read_csv(stat_path)
        missing = [c for c in STAT_COLUMNS if c not in stat.columns]
        if missing:
            raise CsvFormatError(f"{stat_path}: not the authors' stat layout (missing "
                                 f"{missing[:5]}{'...' if len(missing) > 5 else ''})")
        try:
            for c in ("config_idx", *PAPER_FEATURES):
                stat[c] = np.array([float(v) for v in stat[c]], dtype=np.float64)
        except ValueError as exc:
            raise CsvFormatError(f"{stat_path}: {exc}") from None
    ts = None
    if ts_path is not None:
        ts = _read_csv(ts_path)
        need = [c for c in ("packet_time", "packet_size", "packet_dir", "Label") if c not in ts.columns]
        if need:
            raise CsvFormatError(f"{ts_path}: not the authors' ts layout (missing {need})")

    if ts is not None:
        tok, lens = _split_lists(ts["packet_time"], ts_path, "packet_time")
        ns = _time_tokens_ns(tok, ts_path)
        stok, slens = _split_lists(ts["packet_size"], ts_path, "packet_size")
        dtok, dlens = _split_lists(ts["packet_dir"], ts_path, "packet_dir")
        if not (np.array_equal(lens, slens) and np.array_equal(lens, dlens)):
            raise CsvFormatError(f"{ts_path}: packet_time, packet_size and packet_dir lists differ in length")
        sizes, dirs = _int_tokens(stok, ts_path, "packet_size"), _int_tokens(dtok, ts_path, "packet_dir")
        if "packet_flag" in ts.columns:
            ftok, flens = _split_lists(ts["packet_flag"], ts_path, "packet_flag")
            if not np.array_equal(lens, flens):
                raise CsvFormatError(f"{ts_path}: packet_flag lists differ in length from packet_time")
            flags, no_flags = _flag_tokens(ftok), None
        else:
            flags, no_flags = np.zeros(0, dtype=np.int16), np.ones(len(ts), dtype=bool)
            lacks.append("seq_flags")
        label_text = ts["Label"].astype(str)
        n = len(ts)
    else:
        n = len(stat)
        lacks += ["sequences (no ts file)", "first_ts"]
        label_text = stat["Label"].astype(str)

    # the stat rows are the ts rows of >= 10 packets, in order
    row_of_stat = np.arange(n)
    if stat is not None and ts is not None:
        long = np.flatnonzero(lens >= STAT_MIN_PACKETS)
        tp = stat["Total Packets"].to_numpy(dtype=np.float64)
        same_labels = (label_text.iloc[long].to_numpy() == stat["Label"].astype(str).to_numpy()).all()
        if len(long) != len(stat) or not np.array_equal(lens[long], tp) or not same_labels:
            raise CsvFormatError(f"{stat_path} and {ts_path}: the stat rows are not the ts rows of >= "
                                 f"{STAT_MIN_PACKETS} packets in order")
        row_of_stat = long
    elif stat is None:
        row_of_stat = np.zeros(0, dtype=np.int64)
        lacks += ["src_ip/dst_ip (no stat file)", "features (no stat file)", "axes (no stat file)"]

    parts = label_text.str.split("|", n=1, expand=True)
    label = parts[0]
    config = parts[1] if parts.shape[1] > 1 else pd.Series([None] * n)
    if config.isna().all():
        lacks.append("config (only the _cfg variants carry it)")
    out = pd.DataFrame(index=np.arange(n))
    out["run_id"] = None
    out["config"] = config.where(config.notna(), None).to_numpy(dtype=object)
    out["seed"] = pd.array([None] * n, dtype="Int64")
    out["view"] = None
    out["flow_id"] = np.arange(n, dtype=np.int64)
    for c in ("src_ip", "dst_ip", "capture_point"):
        out[c] = None
    for c in ("src_port", "dst_port", "protocol"):
        out[c] = pd.array([None] * n, dtype="Int64")
    axes = {"attacks": None, "n_uav": None, "n_bs": None, "payload": None, "pathloss": None, "modulation": None,
            "mission": None, "tx_dbm": None, "noise_dbm": None}  # fmt: skip
    for k in axes:
        out[k] = None
    out["attacks"] = [c.split("-", 1)[0] if isinstance(c, str) else None for c in out["config"]]
    if stat is not None:
        r = row_of_stat
        cidx = stat["config_idx"].to_numpy()
        out.loc[r, "run_id"] = [str(int(c)) for c in cidx]  # written as an integer by their script
        out.loc[r, "src_ip"] = stat["src_ip"].to_numpy()
        out.loc[r, "dst_ip"] = stat["dst_ip"].to_numpy()
        for ours, theirs, conv in (("n_uav", "num_drones", int), ("n_bs", "num_bs", int), ("payload", "payload", str),
                                   ("pathloss", "pathloss", str), ("modulation", "modulation", str),
                                   ("mission", "mission", str), ("tx_dbm", "tx_power", int),
                                   ("noise_dbm", "noise", lambda v: -float(v))):  # fmt: skip
            try:
                out.loc[r, ours] = [conv(v) if isinstance(v, str) and v != "" else None for v in stat[theirs]]
            except ValueError:
                raise CsvFormatError(f"{stat_path}: column '{theirs}' holds a value that is not a number") from None
        if ts is not None:  # flows under 10 packets: the run of the stat rows around them, when they agree
            rid = out["run_id"]
            before, after = rid.ffill(), rid.bfill()
            same = before.notna() & (before == after)
            out.loc[same & rid.isna(), "run_id"] = before[same & rid.isna()]
            for k in ("n_uav", "n_bs", "payload", "pathloss", "modulation", "mission", "tx_dbm", "noise_dbm"):
                b = out[k].ffill()
                fill = same & out[k].isna()
                out.loc[fill, k] = b[fill]
            if (~same & rid.isna()).any():
                lacks.append("run_id of some flows under 10 packets (between two runs)")
        notes.append(f"{len(stat)} flows with features from {stat_path.name}")
    out["run_id"] = out["run_id"].fillna("unknown")
    out = out.astype({"n_uav": "Int64", "n_bs": "Int64", "tx_dbm": "Int64", "noise_dbm": "Float64"})

    if ts is not None:
        first = np.concatenate(([0], np.cumsum(lens)))[:-1]
        g = np.repeat(np.arange(n), lens)
        has = lens > 0
        first_ns = np.where(has, ns[np.minimum(first, max(len(ns) - 1, 0))] if len(ns) else 0, 0)
        last_ns = np.where(has, ns[np.minimum(first + lens - 1, max(len(ns) - 1, 0))] if len(ns) else 0, 0)
        out["first_ts_ns"] = pd.array(np.where(has, first_ns, 0), dtype="Int64")
        out.loc[~has, "first_ts_ns"] = pd.NA
        out["first_ts"] = np.where(has, ns_to_s(first_ns), np.nan)
        out["last_ts"] = np.where(has, ns_to_s(last_ns), np.nan)
        out["packets"] = lens
        out["bytes"] = np.bincount(g, weights=sizes.astype(np.float64), minlength=n).astype(np.int64)
        out["duration_s"] = np.where(has, (last_ns - first_ns) / 1e9, np.nan)
        rel = (ns - first_ns[g]) / 1e9 if len(ns) else np.zeros(0)
        out["seq_time_s"] = _list_array(rel, lens, pa.float64())
        out["seq_size"] = _list_array(sizes.astype(np.int32), lens, pa.int32())
        if no_flags is None:
            out["seq_flags"] = _list_array(flags, lens, pa.int16())
        else:
            out["seq_flags"] = _list_array(np.zeros(0, dtype=np.int16), np.zeros(n, dtype=np.int64), pa.int16(),
                                           null=no_flags)
        out["seq_dir"] = _list_array(np.where(dirs == 0, 1, -1).astype(np.int8), lens, pa.int8())
    else:
        for c in ("first_ts", "last_ts"):
            out[c] = np.nan
        out["first_ts_ns"] = pd.array([None] * n, dtype="Int64")
        out["packets"] = stat["Total Packets"].to_numpy(dtype=np.int64)
        out["bytes"] = stat["Total Length of Packets"].to_numpy(dtype=np.int64)
        out["duration_s"] = stat["Flow Duration"].to_numpy(dtype=np.float64)
        empty = np.ones(n, dtype=bool)
        z = np.zeros(n, dtype=np.int64)
        out["seq_time_s"] = _list_array(np.zeros(0), z, pa.float64(), null=empty)
        out["seq_size"] = _list_array(np.zeros(0, dtype=np.int32), z, pa.int32(), null=empty)
        out["seq_flags"] = _list_array(np.zeros(0, dtype=np.int16), z, pa.int16(), null=empty)
        out["seq_dir"] = _list_array(np.zeros(0, dtype=np.int8), z, pa.int8(), null=empty)
    for f in PAPER_FEATURES:
        col = np.full(n, np.nan)
        if stat is not None:
            col[row_of_stat] = stat[f].to_numpy(dtype=np.float64)
        out[f] = col
    if ts is not None and stat is not None and len(row_of_stat) < n:
        notes.append(f"{n - len(row_of_stat)} flows under {STAT_MIN_PACKETS} packets have sequences but no features")
    # The layout has no per-packet ground truth: the effect columns are null, not zero.
    out["seq_effect"] = _list_array(np.zeros(0, dtype=object), np.zeros(n, dtype=np.int64), pa.string(),
                                    null=np.ones(n, dtype=bool))
    for c in TRUTH_COLUMNS:
        out[c] = np.full(n, np.nan) if c == "attack_fraction" else pd.array([None] * n, dtype="Int64")
    out["label"] = label.to_numpy(dtype=object)
    for fam, hit in _families(label).items():
        out[f"label_{fam}"] = hit
    out["label_source"] = "uavcas-csv"
    out.attrs["feature_standard"] = PAPER.name
    files = [str(p) for p in (stat_path, ts_path) if p is not None]
    return Imported(out, lacks, notes, files)

