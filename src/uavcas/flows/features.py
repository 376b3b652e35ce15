"""One row per flow: identity, counts, per-packet sequences and the 47 features of a standard.

Identity: src = the forward endpoint (rule 6 of `uavcas.flows.assemble`), ports and protocol
(0 in the host-pair view), first_ts/last_ts (float Unix s) and first_ts_ns (exact int ns), the
capture point. Counts: packets, bytes (frame bytes on the wire), duration_s.
Features: the columns of the named feature standard (`uavcas.flows.standards`: one module per
standard, each with its definitions, units and source).

Sequences (Arrow list columns, one element per packet in flow order, whatever the standard):
seq_time_s float64 (time since the flow's first packet; first_ts_ns + round(seq_time_s * 1e9)
gives each packet's exact ns), seq_size int32 (frame length), seq_flags int16 (TCP flags, 0 for
non-TCP), seq_dir int8 (+1 forward, -1 backward).
"""

from __future__ import annotations

import numpy as np
import pandas as pd
import pyarrow as pa

from .assemble import HOST_VIEWS, Flows
from .packets import PacketTable, addresses_to_str, ns_to_s
from .standards import DEFAULT_STANDARD, FlowPackets
from .standards import standard as feature_standard

CSV_LEAD_COLUMNS: tuple[str, ...] = (
    "src_ip", "src_port", "dst_ip", "dst_port", "protocol", "packets", "bytes", "duration_s",
)  # fmt: skip


def _list_column(values: np.ndarray, starts: np.ndarray, pa_type: pa.DataType) -> pd.api.extensions.ExtensionArray:
    arr = pa.ListArray.from_arrays(pa.array(starts.astype(np.int32)), pa.array(values, type=pa_type))
    return pd.arrays.ArrowExtensionArray(arr)


def flow_frame(p: PacketTable, fl: Flows, sequences: bool = True, standard: str = DEFAULT_STANDARD) -> pd.DataFrame:
    """One row per flow: identity, counts, (optionally) sequences, then the standard's features."""
    std = feature_standard(standard)  # an unknown name fails here, before any work
    n = fl.n_flows
    o, g, fwd, starts = fl.order, fl.flow, fl.fwd, fl.starts
    ts = p["ts_ns"][o]
    size = p["frame_len"][o]
    flags = p["tcp_flags"][o]

    first_ns = ts[starts[:-1]] if n else np.zeros(0, dtype=np.int64)
    last_ns = ts[starts[1:] - 1] if n else np.zeros(0, dtype=np.int64)
    # Identity: the forward endpoint is the first packet's source, or its destination when the
    # first packet travels backward (a SYN-ACK whose SYN was not captured) or, under `cic`, when a
    # flow continued after the flow timeout keeps the old orientation (`Flows.turned`).
    first = o[starts[:-1]] if n else np.zeros(0, dtype=np.int64)
    first_fwd = fl.first_sent_forward if n else np.zeros(0, dtype=bool)
    s_hi = np.where(first_fwd, p["src_hi"][first], p["dst_hi"][first])
    s_lo = np.where(first_fwd, p["src_lo"][first], p["dst_lo"][first])
    d_hi = np.where(first_fwd, p["dst_hi"][first], p["src_hi"][first])
    d_lo = np.where(first_fwd, p["dst_lo"][first], p["src_lo"][first])
    sport = np.where(first_fwd, p["sport"][first], p["dport"][first]).astype(np.int32)
    dport = np.where(first_fwd, p["dport"][first], p["sport"][first]).astype(np.int32)
    proto = p["proto"][first].astype(np.int16)
    if fl.config.view in HOST_VIEWS:  # ports and protocol are not part of a host-pair key
        sport, dport, proto = np.zeros_like(sport), np.zeros_like(dport), np.zeros_like(proto)
    src_ip, dst_ip = addresses_to_str(s_hi, s_lo), addresses_to_str(d_hi, d_lo)
    cols: dict[str, object] = {
        "flow_id": np.arange(n, dtype=np.int64),
        "src_ip": src_ip,
        "src_port": sport,
        "dst_ip": dst_ip,
        "dst_port": dport,
        "protocol": proto,
        "first_ts": ns_to_s(first_ns),
        "last_ts": ns_to_s(last_ns),
        "first_ts_ns": first_ns.astype(np.int64),
        "capture_point": np.asarray(p.points, dtype=object)[fl.point] if n else np.zeros(0, dtype=object),
        "packets": np.diff(starts).astype(np.int64),
        "bytes": np.bincount(g, weights=size.astype(np.float64), minlength=n).astype(np.int64),
        "duration_s": (last_ns - first_ns) / 1e9,
    }
    df = pd.DataFrame(cols)
    for c in ("src_ip", "dst_ip", "capture_point"):
        df[c] = df[c].astype(object)
    if sequences:
        rel = (ts - first_ns[g]) / 1e9 if n else ts.astype(np.float64)
        df["seq_time_s"] = _list_column(rel, starts, pa.float64())
        df["seq_size"] = _list_column(size.astype(np.int32), starts, pa.int32())
        df["seq_flags"] = _list_column(flags.astype(np.int16), starts, pa.int16())
        df["seq_dir"] = _list_column(np.where(fwd, 1, -1).astype(np.int8), starts, pa.int8())
    feat_df = pd.DataFrame(std.features(FlowPackets(p, fl, src_ip, dst_ip)))
    out = pd.concat([df, feat_df], axis=1)
    out.attrs["feature_standard"] = std.name
    return out
