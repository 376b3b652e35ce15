"""Arrow schema of `flows.parquet` (column names from `schema.py`, dtypes fixed here) and I/O.

Dtypes: identity strings are `string`; ports int32, protocol int16, seed/flow_id/packets/bytes
int64; first_ts/last_ts float64 Unix seconds, first_ts_ns int64 Unix nanoseconds (exact);
duration_s float64; axis columns as Scenario.axes() gives them (n_uav, n_bs, tx_dbm int64;
noise_dbm float64; attacks, payload, pathloss, modulation, mission string); sequences are list
columns: seq_time_s list<float64>, seq_size list<int32>, seq_flags list<int16>, seq_dir list<int8>
(+1 forward, -1 backward), seq_effect list<string> (one of vocabulary.EFFECTS per packet); the
features of the dataset's standard float64 (`uavcas.flows.standards`); attack_packets, provoked_packets and
attack_packets_<family> int64, attack_fraction float64; label_<family> bool; label, label_source string;
the context columns (`schema.CONTEXT_FEATURES`, all or none) float64. Every field carries its
data-dictionary entry (`uavcas.dataset.dictionary`) as field metadata: b"unit", b"meaning". A window-host shard
(episodes, `uavcas.labels.episodes`) has its own columns instead: `episode_arrow_schema`. Any column may hold nulls
where the source did not carry the value (an imported CSV has no ports, for instance).

Files are written from Arrow arrays without pandas metadata, so plain `pandas.read_parquet` reads
every file (list columns come back as object columns of arrays).
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pandas as pd
import pyarrow as pa
import pyarrow.parquet as pq

from uavcas.atomic import atomic_path
from uavcas.flows.standards import DEFAULT_STANDARD, episode_feature_columns, feature_columns
from uavcas.schema import (
    AXIS_COLUMNS,
    CONTEXT_FEATURES,
    COUNT_COLUMNS,
    EPISODE_CONTEXT_FEATURES,
    EPISODE_ID_COLUMNS,
    EPISODE_PACKET_UNITS,
    ID_COLUMNS,
    LABEL_COLUMNS,
    SEQUENCE_COLUMNS,
    TRUTH_COLUMNS,
)

from .dictionary import field_metadata

_ID_TYPES = {
    "run_id": pa.string(),
    "config": pa.string(),
    "seed": pa.int64(),
    "view": pa.string(),
    "flow_id": pa.int64(),
    "src_ip": pa.string(),
    "src_port": pa.int32(),
    "dst_ip": pa.string(),
    "dst_port": pa.int32(),
    "protocol": pa.int16(),
    "first_ts": pa.float64(),
    "last_ts": pa.float64(),
    "first_ts_ns": pa.int64(),
    "capture_point": pa.string(),
}
_AXIS_TYPES = {
    "attacks": pa.string(),
    "n_uav": pa.int64(),
    "n_bs": pa.int64(),
    "payload": pa.string(),
    "pathloss": pa.string(),
    "modulation": pa.string(),
    "mission": pa.string(),
    "tx_dbm": pa.int64(),
    "noise_dbm": pa.float64(),
}
_COUNT_TYPES = {"packets": pa.int64(), "bytes": pa.int64(), "duration_s": pa.float64()}
_SEQ_TYPES = {
    "seq_time_s": pa.list_(pa.float64()),
    "seq_size": pa.list_(pa.int32()),
    "seq_flags": pa.list_(pa.int16()),
    "seq_dir": pa.list_(pa.int8()),
    "seq_effect": pa.list_(pa.string()),
}
META_KEY = b"uavcas"


def _described(fields: list[pa.Field], standard: str, episodes: bool) -> pa.Schema:
    """The fields with their data-dictionary entry (unit, meaning) as Parquet field metadata."""
    return pa.schema([f.with_metadata(field_metadata(f.name, standard, episodes)) for f in fields])


def with_dictionary(table: pa.Table, standard: str) -> pa.Table:
    """`table` with every field's data-dictionary metadata (a union of shards written before the
    dictionary existed gets it too)."""
    schema = _described(list(table.schema), standard, episodes=table.schema.get_field_index("host") >= 0)
    return table.cast(schema.with_metadata(table.schema.metadata))


def arrow_schema(standard: str = DEFAULT_STANDARD, context: bool = False) -> pa.Schema:
    """The columns of a shard: `context` adds the ctx_* columns after the features."""
    fields = [pa.field(c, _ID_TYPES[c]) for c in ID_COLUMNS]
    fields += [pa.field(c, _AXIS_TYPES[c]) for c in AXIS_COLUMNS]
    fields += [pa.field(c, _COUNT_TYPES[c]) for c in COUNT_COLUMNS]
    fields += [pa.field(c, _SEQ_TYPES[c]) for c in SEQUENCE_COLUMNS]
    fields += [pa.field(c, pa.float64()) for c in feature_columns(standard)]
    fields += [pa.field(c, pa.float64()) for c in (CONTEXT_FEATURES if context else ())]
    fields += [pa.field(c, pa.float64() if c == "attack_fraction" else pa.int64()) for c in TRUTH_COLUMNS]
    fields += [pa.field(c, pa.bool_()) for c in LABEL_COLUMNS]
    fields += [pa.field("label", pa.string()), pa.field("label_source", pa.string())]
    return _described(fields, standard, episodes=False)


COLUMNS: tuple[str, ...] = tuple(arrow_schema().names)
_EPISODE_ID_TYPES = {**_ID_TYPES, "host": pa.string(), "host_ip": pa.string(), "window": pa.int64()}
# counts of packets, bytes, peers, ports and flows are integers; rates, shares, spans and summaries floats
_EPISODE_INT_UNITS = ("packets", "bytes", "hosts", "ports", "flows")


def episode_arrow_schema(standard: str = DEFAULT_STANDARD, context: bool = False) -> pa.Schema:
    """The columns of a window-host shard (`uavcas.labels.episodes`): identity, axes, packets,
    the episode features (`FeatureStandard.episode_columns`), the summarised context columns
    when `context`, then the same truth and label columns as flows."""
    fields = [pa.field(c, _EPISODE_ID_TYPES[c]) for c in EPISODE_ID_COLUMNS]
    fields += [pa.field(c, _AXIS_TYPES[c]) for c in AXIS_COLUMNS]
    fields += [pa.field("packets", pa.int64())]
    fields += [pa.field(c, pa.int64() if EPISODE_PACKET_UNITS.get(c) in _EPISODE_INT_UNITS else pa.float64())
               for c in episode_feature_columns(standard)]
    fields += [pa.field(c, pa.float64()) for c in (EPISODE_CONTEXT_FEATURES if context else ())]
    fields += [pa.field(c, pa.float64() if c == "attack_fraction" else pa.int64()) for c in TRUTH_COLUMNS]
    fields += [pa.field(c, pa.bool_()) for c in LABEL_COLUMNS]
    fields += [pa.field("label", pa.string()), pa.field("label_source", pa.string())]
    return _described(fields, standard, episodes=True)


def is_episode_frame(df: pd.DataFrame) -> bool:
    """A window-host frame (rows are node-windows, `host` names the node), not a flow frame."""
    return "host" in df.columns


def to_table(df: pd.DataFrame, meta: dict | None = None, standard: str | None = None) -> pa.Table:
    """DataFrame with every schema column -> Arrow table in schema order and dtypes.

    `standard` (default: `df.attrs["feature_standard"]`, else 'cic') picks the feature columns; the
    context columns are written when `df` has them (all of them, or none).
    """
    standard = standard or df.attrs.get("feature_standard", DEFAULT_STANDARD)
    episodes = is_episode_frame(df)
    all_ctx = EPISODE_CONTEXT_FEATURES if episodes else CONTEXT_FEATURES
    ctx = [c for c in all_ctx if c in df.columns]
    if ctx and len(ctx) != len(all_ctx):
        missing = [c for c in all_ctx if c not in df.columns]
        raise ValueError(f"flow frame has some context columns but lacks {missing}")
    schema = (episode_arrow_schema if episodes else arrow_schema)(standard, context=bool(ctx))
    missing = [c for c in schema.names if c not in df.columns]
    if missing:
        raise ValueError(f"flow frame lacks schema columns ({standard} features): {missing}")
    arrays = []
    for f in schema:
        col = df[f.name]
        if isinstance(col.dtype, pd.ArrowDtype):
            arr = pa.array(col.array)
        elif f.name in _SEQ_TYPES and col.dtype == object:
            arr = pa.array([None if v is None or (isinstance(v, float) and np.isnan(v)) else list(v) for v in col],
                           type=f.type)
        else:
            arr = pa.array(col.to_numpy(), from_pandas=True)
        if isinstance(arr, pa.ChunkedArray):
            arr = arr.combine_chunks()
        arrays.append(arr.cast(f.type))
    table = pa.Table.from_arrays(arrays, schema=schema)
    meta = dict(meta or {}, feature_standard=standard)
    return table.replace_schema_metadata({META_KEY: json.dumps(meta, sort_keys=True).encode()})


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
