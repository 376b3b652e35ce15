"""Arrow schema of `flows.parquet` (column names from `schema.py`, dtypes from the view, `uavcas.views`) and I/O.

Dtypes: identity strings are `string`; ports int32, protocol int16, seed/flow_id/packets/bytes
int64; first_ts/last_ts float64 Unix seconds, first_ts_ns int64 Unix nanoseconds (exact);
duration_s float64; axis columns as Scenario.axes() gives them (n_uav, n_bs, tx_dbm int64;
noise_dbm float64; attacks, payload, pathloss, modulation, mission string); sequences are list
columns: seq_time_s list<float64>, seq_size list<int32>, seq_flags list<int16>, seq_dir list<int8>
(+1 forward, -1 backward), seq_effect list<string> (one of vocabulary.EFFECTS per packet); the
features of the dataset's standard float64 (`uavcas.flows.standards`); attack_packets, provoked_packets and
attack_packets_<family> int64, attack_fraction float64; label_<family> bool; label, label_source string;
the context columns (`schema.CONTEXT_FEATURES`, all or none) float64. Every field carries its
data-dictionary entry (`uavcas.dataset.dictionary`) as field metadata: b"unit", b"meaning". Those are
the columns of a flow view; another view (`uavcas.views`: the window-host view's episodes, say) has its
own (`ViewSpec.fields`, `arrow_schema(view=...)`). Any column may hold nulls where the source did
not carry the value (an imported CSV has no ports, for instance).

Every shard is written by `write_shard`, from its rows and its metadata, which names its feature
standard and its view.

Files are written from Arrow arrays without pandas metadata, so plain `pandas.read_parquet` reads
every file (list columns come back as object columns of arrays).
"""

from __future__ import annotations

import json
from collections.abc import Mapping
from pathlib import Path
from typing import Any, BinaryIO

import numpy as np
import pandas as pd
import pyarrow as pa
import pyarrow.parquet as pq

from uavcas.atomic import atomic_path
from uavcas.flows.standards import DEFAULT_STANDARD
from uavcas.views import DEFAULT_VIEW, ViewSpec, recorded_view
from uavcas.views import view as view_spec

from .dictionary import field_metadata

META_KEY = b"uavcas"


def _described(fields: list[pa.Field], standard: str, view: ViewSpec) -> pa.Schema:
    """The fields with their data-dictionary entry (unit, meaning) as Parquet field metadata."""
    return pa.schema([f.with_metadata(field_metadata(f.name, standard, view)) for f in fields])


def with_dictionary(table: pa.Table, standard: str, view: ViewSpec) -> pa.Table:
    """`table` with every field's data-dictionary metadata (a union of shards written before the
    dictionary existed gets it too)."""
    return table.cast(_described(list(table.schema), standard, view).with_metadata(table.schema.metadata))


def arrow_schema(standard: str = DEFAULT_STANDARD, context: bool = False, view: str = DEFAULT_VIEW) -> pa.Schema:
    """The columns of a shard of `view` (`uavcas.views`; default: 5-tuple flows): `context` adds
    the view's ctx_* columns after the features."""
    spec = view_spec(view)
    return _described(spec.fields(standard, context), standard, spec)


COLUMNS: tuple[str, ...] = tuple(arrow_schema().names)


def shard_table(frame: pd.DataFrame, meta: Mapping[str, Any]) -> pa.Table:
    """The one shard writer's table (`write_shard`): `frame` (one run's rows, every column of its
    view) in its view's columns and dtypes, `meta` as the file's metadata.

    The feature standard and the view are the shard's own record, `meta["features"]` and
    `meta["view"]` (`uavcas.extract.ShardInfo`; no view: flows), never guessed from the frame (a
    frame's `attrs` do not survive `pd.concat`); the context columns are written when `frame` has them (all of
    them, or none).
    """
    if not meta.get("features"):
        raise ValueError("shard metadata lacks 'features': a shard's feature standard is recorded, never guessed")
    standard, view = str(meta["features"]), recorded_view(meta)  # no view recorded (an import): flows
    ctx = [c for c in view.context_columns if c in frame.columns]
    if ctx and len(ctx) != len(view.context_columns):
        missing = [c for c in view.context_columns if c not in frame.columns]
        raise ValueError(f"{view.row.singular} frame has some context columns but lacks {missing}")
    schema = _described(view.fields(standard, bool(ctx)), standard, view)
    missing = [c for c in schema.names if c not in frame.columns]
    if missing:
        raise ValueError(f"{view.row.singular} frame lacks schema columns ({standard} features): {missing}")
    arrays = []
    for f in schema:
        col = frame[f.name]
        if isinstance(col.dtype, pd.ArrowDtype):
            arr = pa.array(col.array)
        elif pa.types.is_list(f.type) and col.dtype == object:
            arr = pa.array([None if v is None or (isinstance(v, float) and np.isnan(v)) else list(v) for v in col],
                           type=f.type)
        else:
            arr = pa.array(col.to_numpy(), from_pandas=True)
        if isinstance(arr, pa.ChunkedArray):
            arr = arr.combine_chunks()
        arrays.append(arr.cast(f.type))
    table = pa.Table.from_arrays(arrays, schema=schema)
    stored = dict(meta, feature_standard=standard)
    return table.replace_schema_metadata({META_KEY: json.dumps(stored, sort_keys=True).encode()})


def write_shard(frame: pd.DataFrame, meta: Mapping[str, Any], dest: Path | BinaryIO) -> None:
    """Write one run's shard (`shard_table`) to `dest`: a path (atomically) or a binary buffer
    (a campaign run's result, sent back to be committed)."""
    table = shard_table(frame, meta)
    if isinstance(dest, Path):
        write_table(table, dest)
    else:
        pq.write_table(table, dest, compression="zstd")


def table_standard(table_or_schema) -> str:
    """The feature standard a table / file schema was written with ('cic' for files before v2)."""
    schema = getattr(table_or_schema, "schema", table_or_schema)
    md = schema.metadata or {}
    return json.loads(md[META_KEY]).get("feature_standard", DEFAULT_STANDARD) if META_KEY in md else DEFAULT_STANDARD


def frame_to_arrow(df: pd.DataFrame) -> pa.Table:
    """Any flow frame (e.g. `uavcas flows` output) -> Arrow table without pandas metadata."""
    arrays, names = [], []
    for c in df.columns:
        col = df[c]
        arr = (pa.array(col.array) if isinstance(col.dtype, pd.ArrowDtype)
               else pa.array(col.to_numpy(), from_pandas=True))
        arrays.append(arr.combine_chunks() if isinstance(arr, pa.ChunkedArray) else arr)
        names.append(str(c))
    return pa.Table.from_arrays(arrays, names=names)


def write_table(table: pa.Table, path: Path) -> None:
    with atomic_path(path) as tmp:
        pq.write_table(table, tmp, compression="zstd")


def table_meta(path: Path) -> dict:
    md = pq.read_schema(path).metadata or {}
    return json.loads(md[META_KEY]) if META_KEY in md else {}


def read_flows(path: str | Path, columns: list[str] | None = None) -> pd.DataFrame:
    """Read flows.parquet (or a shard); list columns stay Arrow-backed (no per-row Python lists).

    `df.attrs["feature_standard"]` names the standard of its feature columns.
    """
    table = pq.read_table(path, columns=columns)
    df = table.to_pandas(types_mapper=lambda t: pd.ArrowDtype(t) if pa.types.is_list(t) else None)
    df.attrs["feature_standard"] = table_standard(table)
    return df
