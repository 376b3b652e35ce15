"""The files of `uavcas flows`: a stream of flow frames (`uavcas.flows.iter_flow_frames`) written
as Parquet or CSV, one frame at a time (memory bounded by a frame, not by the capture).

- Parquet (`write_parquet`): every column of the frames (sequences included), zstd, one row group
  per frame; no flow at all still gives a valid file with the flow schema and no row.
- CSV (`write_csv`): the lead columns (`uavcas.flows.CSV_LEAD_COLUMNS`), the standard's 47
  features, `first_ts` / `last_ts` as exact decimal seconds (9 digits: a float64 would keep ~10 us
  of a Unix time), `capture_point`. Written by Arrow's CSV writer (fast; strings quoted only when
  they need it), the header by hand so that it is the same for an empty stream.
"""

from __future__ import annotations

from collections.abc import Iterable
from pathlib import Path
from typing import BinaryIO

import numpy as np
import pandas as pd
import pyarrow as pa
import pyarrow.csv as pacsv
import pyarrow.parquet as pq

from uavcas.atomic import atomic_path
from uavcas.flows import CSV_LEAD_COLUMNS, empty_flow_frame
from uavcas.flows.standards import feature_columns

from .parquet import frame_to_arrow


def ns_decimal(ns) -> pa.Array:
    """int64 Unix ns -> Arrow decimal128(28, 9) seconds: exact, written with all 9 digits."""
    ns = np.asarray(ns, dtype=np.int64)
    words = np.zeros((ns.shape[0], 2), dtype=np.int64)
    words[:, 0], words[:, 1] = ns, np.where(ns < 0, -1, 0)  # the unscaled 128-bit integer, two's complement
    return pa.Array.from_buffers(pa.decimal128(28, 9), ns.shape[0], [None, pa.py_buffer(words.tobytes())])


def csv_table(df: pd.DataFrame, standard: str) -> pa.Table:
    """The CSV columns of a flow frame as an Arrow table (Arrow's writer is what keeps CSV fast)."""
    t = frame_to_arrow(df[list(CSV_LEAD_COLUMNS) + list(feature_columns(standard))])
    first = df["first_ts_ns"].to_numpy()
    last = first + (df["duration_s"].to_numpy() * 1e9).round().astype("int64")
    t = t.append_column("first_ts", ns_decimal(first)).append_column("last_ts", ns_decimal(last))
    return t.append_column("capture_point", pa.array(df["capture_point"].astype(str).tolist(), pa.string()))


def write_parquet(frames: Iterable[pd.DataFrame], path: Path, standard: str) -> int:
    """Write the frames to one Parquet file at `path` (atomically); the number of flows written."""
    n = 0
    with atomic_path(path) as tmp:
        writer = None
        for df in frames:
            t = frame_to_arrow(df)
            writer = writer or pq.ParquetWriter(tmp, t.schema, compression="zstd")
            writer.write_table(t.cast(writer.schema))
            n += len(df)
        if writer is None:  # no flow at all: still a valid (empty) file
            writer = pq.ParquetWriter(tmp, frame_to_arrow(empty_flow_frame(standard)).schema)
        writer.close()
    return n


def _write_csv_to(frames: Iterable[pd.DataFrame], fh: BinaryIO, standard: str) -> int:
    # the header plain (fixed names, no commas), the rows by Arrow (strings quoted)
    opts = pacsv.WriteOptions(include_header=False, quoting_style="needed")
    writer, n = None, 0
    for df in frames:
        t = csv_table(df, standard)
        if writer is None:
            fh.write((",".join(t.schema.names) + "\n").encode())
            writer = pacsv.CSVWriter(fh, t.schema, write_options=opts)
        writer.write_table(t)
        n += len(df)
    if writer is None:  # no flow: the header alone
        fh.write((",".join(csv_table(empty_flow_frame(standard), standard).schema.names) + "\n").encode())
    else:
        writer.close()
    return n


def write_csv(frames: Iterable[pd.DataFrame], dest: Path | BinaryIO, standard: str) -> int:
    """Write the frames as CSV to a file (atomically) or to an open binary stream (standard
    output: left open); the number of flows written."""
    if not isinstance(dest, (str, Path)):
        return _write_csv_to(frames, dest, standard)
    with atomic_path(dest) as tmp, open(tmp, "wb") as fh:
        return _write_csv_to(frames, fh, standard)
