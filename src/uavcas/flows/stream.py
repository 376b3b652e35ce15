"""Streaming extraction: a capture read in blocks, flows carried across block boundaries.

Each block's packets are assembled together with the packets of the flows still open after the
previous block (`uavcas.flows.assemble`, whose termination rules only look backwards in time). A
flow is finished, and its row computed, once no later packet can join it:
- it was closed (`Flows.close_ns`) and the policy's grace period after the close has passed, or
- it is open and the idle timeout has passed since its last packet, or the active timeout since
  its first,
measured against the newest packet seen so far less `REORDER_SLACK_NS` (captures are in arrival
order up to small reorderings), or
- a later flow of the same key has begun (packets go to a key's latest flow). At the end of the
  capture every open flow is finished.
One difference from reading whole: under `--termination cic`, a flow that CICFlowMeter continues
after its 120 s flow timeout keeps its predecessor's orientation; when the predecessor was
released in an earlier block, the continuation takes its own first packet's sender instead. Rows are
released in order of first packet (flow_id continues across blocks): a finished flow waits while
an earlier-starting flow is still open.

Memory is then bounded by one block, the packets of the open flows (bounded by the timeouts),
and the finished rows waiting for an earlier flow to end, not by the capture's size. Views
without termination (`hostpair`) keep every flow open until the end, and several capture points
are de-duplicated across files (`assemble` rule 2): both need every packet at once, so
`iter_flow_frames` then reads them into memory (still block by block, never the whole file) and
yields one frame.
"""

from __future__ import annotations

from collections.abc import Iterator, Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np
import pandas as pd

from .assemble import FlowConfig, Flows, assemble, select_flows
from .features import flow_frame
from .packets import COLUMNS, CaptureStats, PacketTable, Truncation, empty_columns, iter_packet_blocks, read_packets
from .pcapio import CHUNK_BYTES
from .standards import DEFAULT_STANDARD

REORDER_SLACK_NS = 1_000_000_000
_UNLIMITED = 1 << 62


@dataclass
class StreamReport:
    """Filled while a stream is consumed: per-file capture statistics and totals."""

    stats: list[CaptureStats] = field(default_factory=list)
    truncations: list[Truncation] = field(default_factory=list)
    packets: int = 0
    flows: int = 0


def _concat(a: dict[str, np.ndarray], b: dict[str, np.ndarray]) -> dict[str, np.ndarray]:
    if a["ts_ns"].shape[0] == 0:
        return b
    return {c: np.concatenate([a[c], b[c]]) for c in COLUMNS}


def _finished(p: PacketTable, fl: Flows, cfg: FlowConfig, horizon: int | None) -> np.ndarray:
    if horizon is None:
        return np.ones(fl.n_flows, dtype=bool)
    mark = horizon - REORDER_SLACK_NS
    first_ns, last_ns = p["ts_ns"][fl.first], p["ts_ns"][fl.last]
    # a flow followed by another of its key takes no more packets
    latest = np.full(int(fl.key.max()) + 1 if fl.n_flows else 0, -1, dtype=np.int64)
    np.maximum.at(latest, fl.key, np.arange(fl.n_flows))
    done = latest[fl.key] != np.arange(fl.n_flows)
    closed = fl.close_ns >= 0 if fl.close_ns is not None else np.zeros(fl.n_flows, dtype=bool)
    done |= closed & (fl.close_ns + cfg.grace_ns <= mark)
    if cfg.idle_ns is not None:
        done |= ~closed & (last_ns + cfg.idle_ns <= mark)
    if cfg.active_ns is not None:
        done |= ~closed & (first_ns + cfg.active_ns < mark)
    return done


def _stream_one(
    path: Path, point: str, cfg: FlowConfig, standard: str, sequences: bool, report: StreamReport,
    allow_truncated: bool, chunk_bytes: int,
) -> Iterator[pd.DataFrame]:  # fmt: skip
    st = CaptureStats(str(path))
    report.stats.append(st)
    work = replace(cfg, min_packets=1, max_packets=_UNLIMITED)  # caps apply when a flow is finished
    carry = empty_columns()
    waiting: list[pd.DataFrame] = []  # finished rows not yet released, with their sort keys
    horizon: int | None = None
    blocks = iter_packet_blocks(path, 0, st, report.truncations, allow_truncated, chunk_bytes)
    cols = next(blocks, None)
    while cols is not None:
        nxt = next(blocks, None)
        report.packets += cols["ts_ns"].shape[0]
        if cols["ts_ns"].shape[0]:
            top = int(cols["ts_ns"].max())
            horizon = top if horizon is None else max(horizon, top)
        merged = _concat(carry, cols)
        if merged["ts_ns"].shape[0] == 0:
            cols = nxt
            continue
        p = PacketTable(merged, (point,))
        fl = assemble(p, work)
        done = _finished(p, fl, cfg, None if nxt is None else horizon)
        open_pk = fl.order[np.repeat(~done, np.diff(fl.starts))]
        carry = {c: merged[c][np.sort(open_pk)] for c in COLUMNS}
        sub = select_flows(fl, done, cfg.max_packets, cfg.effective_min_packets)
        if sub.n_flows:
            rows = flow_frame(p, sub, sequences=sequences, standard=standard)
            rows["_frame"] = p["frame_index"][sub.first]
            waiting.append(rows)
        if waiting:
            pend = pd.concat(waiting, ignore_index=True) if len(waiting) > 1 else waiting[0]
            pend = pend.sort_values(["first_ts_ns", "_frame"], kind="stable").reset_index(drop=True)
            cut = len(pend)
            if nxt is not None and (~done).any():  # rows starting after the earliest open flow wait
                f_open = fl.first[~done]
                e = f_open[np.lexsort((p["frame_index"][f_open], p["ts_ns"][f_open]))[0]]
                lim_ns, lim_frame = int(p["ts_ns"][e]), int(p["frame_index"][e])
                ts_w, fr_w = pend["first_ts_ns"].to_numpy(), pend["_frame"].to_numpy()
                cut = int(((ts_w < lim_ns) | ((ts_w == lim_ns) & (fr_w < lim_frame))).sum())
            waiting = [pend.iloc[cut:]] if cut < len(pend) else []
            if cut:
                yield pend.iloc[:cut].drop(columns="_frame").reset_index(drop=True)
        cols = nxt


def empty_flow_frame(standard: str = DEFAULT_STANDARD, sequences: bool = True) -> pd.DataFrame:
    """The columns of a flow frame with no rows: what a capture without a single flow yields
    (its files still carry the schema: a Parquet file with no row, a CSV header)."""
    empty = PacketTable(empty_columns(), ("none",))
    return flow_frame(empty, assemble(empty), sequences=sequences, standard=standard)


def iter_flow_frames(
    paths: Sequence[str | Path],
    cfg: FlowConfig = FlowConfig(),
    standard: str = DEFAULT_STANDARD,
    sequences: bool = True,
    points: Sequence[str] | None = None,
    allow_truncated: bool = False,
    report: StreamReport | None = None,
    chunk_bytes: int = CHUNK_BYTES,
) -> Iterator[pd.DataFrame]:
    """Frames of flows in order of first packet, `flow_id` numbering them across frames.

    One capture file: streamed (bounded memory). Several (capture points to de-duplicate), or flow
    rules that never end a flow (every packet is kept to the end anyway): read into memory, block
    by block, and yielded as one frame.
    """
    paths = [Path(p) for p in paths]
    names = list(points) if points is not None else [p.stem for p in paths]
    report = report if report is not None else StreamReport()
    next_id = 0
    if len(paths) == 1 and cfg.ends_flows:
        frames = _stream_one(paths[0], names[0], cfg, standard, sequences, report, allow_truncated, chunk_bytes)
    else:
        pk = read_packets(paths, names, allow_truncated=allow_truncated, chunk_bytes=chunk_bytes)
        report.stats.extend(pk.stats)
        report.truncations.extend(pk.truncations)
        report.packets += len(pk)
        frames = iter([flow_frame(pk, assemble(pk, cfg), sequences=sequences, standard=standard)])
    for df in frames:
        df["flow_id"] = np.arange(next_id, next_id + len(df), dtype=np.int64)
        next_id += len(df)
        report.flows += len(df)
        df.attrs["feature_standard"] = standard
        yield df
