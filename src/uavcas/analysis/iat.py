"""Inter-arrival times (IATs) of flows from their per-packet time sequences.

Conventions (explicit so nothing is silently dropped):
- IATs are the differences of consecutive `seq_time_s` values in packet order, in seconds.
- A zero IAT (two packets with the same capture timestamp, common for floods at tshark's
  microsecond resolution) is kept: the binning puts it into a dedicated first bin [0, lo).
- A negative IAT can only come from out-of-order timestamps (merging capture points); it is
  counted (`n_negative`) and clipped to 0 so it lands in the zero bin, never discarded.
- Flows with fewer than 2 packets have no IAT and contribute nothing (counted as `n_flows_no_iat`).

Two sources, and a comparison of datasets uses ONE for all of them (like for like):
- `packet`: every IAT of every flow (needs the sequences; external CSVs have none);
- `flow-mean`: one value per flow, its mean IAT: from the sequences when the dataset has them (in
  seconds whatever its feature standard), else its 'Flow IAT Mean' (else 'Fwd IAT Mean') column,
  which the external loaders give in seconds. Comparing our per-packet IATs with another
  dataset's per-flow means compares two different quantities.
`choose_source` picks `packet` when every dataset has sequences, else `flow-mean`.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pandas as pd
import pyarrow as pa

FALLBACK_SOURCES = ("Flow IAT Mean", "Fwd IAT Mean")
IAT_SOURCES = ("packet", "flow-mean")


@dataclass(frozen=True)
class FlowIATs:
    """IATs of a set of flows: one array per flow with an IAT (after clipping) + what was clipped."""

    per_flow: list[np.ndarray]
    n_negative: int
    n_zero: int
    n_flows_no_iat: int
    source: str = "seq_time_s"
    rows: np.ndarray | None = None  # position in the frame of the flow behind each per_flow entry

    @property
    def pooled(self) -> np.ndarray:
        return np.concatenate(self.per_flow) if self.per_flow else np.empty(0)


def _values_offsets(col: pd.Series) -> tuple[np.ndarray, np.ndarray]:
    """Flat values and offsets of a list column (Arrow-backed or object arrays)."""
    if isinstance(col.dtype, pd.ArrowDtype):
        arr = pa.array(col.array)
        if isinstance(arr, pa.ChunkedArray):
            arr = arr.combine_chunks()
        arr = arr.fill_null([])  # a null sequence is an empty one
        offsets = arr.offsets.to_numpy().astype(np.int64)
        values = arr.values.to_numpy(zero_copy_only=False).astype(float)
        return values, offsets
    lengths = np.array([0 if s is None else len(s) for s in col], dtype=np.int64)
    offsets = np.concatenate([[0], np.cumsum(lengths)])
    parts = [np.asarray(s, dtype=float) for s in col if s is not None and len(s)]
    return (np.concatenate(parts) if parts else np.empty(0)), offsets


def iats_of_sequences(col, limit: int | None = None) -> FlowIATs:
    """IATs of each time sequence (the first `limit` IATs of each flow when given)."""
    values, offsets = _values_offsets(col if isinstance(col, pd.Series) else pd.Series(list(col), dtype=object))
    d_all = np.diff(values) if values.size > 1 else np.empty(0)
    starts, ends = offsets[:-1], offsets[1:]
    has = (ends - starts) >= 2
    stop = ends - 1 if limit is None else np.minimum(ends - 1, starts + limit)
    per_flow = [d_all[s:e] for s, e in zip(starts[has], stop[has])]
    pooled = np.concatenate(per_flow) if per_flow else np.empty(0)
    n_neg = int((pooled < 0).sum())
    np.maximum(d_all, 0.0, out=d_all)  # per_flow are views of d_all: clipped in place
    n_zero = int((pooled <= 0).sum())
    return FlowIATs(per_flow, n_neg, n_zero, int((~has).sum()), "seq_time_s", np.flatnonzero(has))


def _per_flow_means(iats: FlowIATs, source: str) -> FlowIATs:
    v = np.array([f.mean() for f in iats.per_flow], dtype=float)
    return FlowIATs([v[i : i + 1] for i in range(len(v))], iats.n_negative, int((v <= 0).sum()),
                    iats.n_flows_no_iat, source, iats.rows)


def has_sequences(df: pd.DataFrame) -> bool:
    return "seq_time_s" in df.columns


def choose_source(frames, requested: str = "auto") -> str:
    """The one IAT source for comparing `frames`: `packet` needs sequences in every frame."""
    if requested not in IAT_SOURCES + ("auto",):
        raise ValueError(f"unknown IAT source {requested!r}; known: {', '.join(IAT_SOURCES)}, auto")
    all_seq = all(has_sequences(f) for f in frames)
    if requested == "auto":
        return "packet" if all_seq else "flow-mean"
    if requested == "packet" and not all_seq:
        raise ValueError("--iat-source packet needs per-packet sequences (seq_time_s) in every dataset; "
                         "an external dataset has none: use --iat-source flow-mean")
    return requested


def flow_iats(df: pd.DataFrame, limit: int | None = None, source: str = "packet") -> FlowIATs:
    """IATs of the flows of a dataset frame from `source` ('packet' or 'flow-mean')."""
    if source not in IAT_SOURCES:
        raise ValueError(f"unknown IAT source {source!r}; known: {', '.join(IAT_SOURCES)}")
    if has_sequences(df):
        iats = iats_of_sequences(df["seq_time_s"], limit=limit)
        return iats if source == "packet" else _per_flow_means(iats, "seq_time_s flow mean")
    if source == "packet":
        raise ValueError("no per-packet sequences (seq_time_s) in this dataset: use the flow-mean IAT source")
    for src in FALLBACK_SOURCES:
        if src in df.columns and df[src].notna().any():
            v = df[src].to_numpy(dtype=float)
            ok = np.isfinite(v)
            v = v[ok]
            neg = int((v < 0).sum())
            v = np.clip(v, 0.0, None)
            return FlowIATs([v[i : i + 1] for i in range(len(v))], neg, int((v == 0).sum()), int((~ok).sum()), src,
                            np.flatnonzero(ok))
    raise ValueError("no IAT source: the frame has neither 'seq_time_s' nor a mean-IAT feature")
