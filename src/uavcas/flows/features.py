"""Per-flow sequences and the 47 CICFlowMeter-named statistics, by numpy segment reductions.

Definitions (units: seconds, bytes = link-layer frame length as tshark's frame.len, per second):
- Flow Duration = last - first packet time. Rates (Flow Bytes/s, Flow Packets/s) = total / duration,
  0 when the duration is 0 (a single packet), so no inf/NaN reaches a model.
- IAT = gaps between consecutive packets of the flow (Flow IAT *), of its forward packets only
  (Fwd IAT *) or backward only (Bwd IAT *). Fwd/Bwd IAT Total = sum of those gaps. No gap -> 0.
- Std = sample standard deviation (n - 1, as CICFlowMeter); 0 with fewer than 2 values.
  Packet Length Variance = Packet Length Std squared. Empty direction -> 0 for its length stats.
- Flag counts = number of packets with the flag set (CWE Flag Count counts CWR, 0x80).
- Down/Up Ratio = backward packets / forward packets (0 when there is no forward packet).
- Average Packet Size = bytes / packets.
- Active/Idle (CICFlowMeter split with schema.ACTIVITY_TIMEOUT_S = 5 s): a gap > 5 s is idle and
  separates active periods; Active Mean = mean active-period length (last - first packet of the
  period), Idle Mean/Max over the idle gaps (0 when there is none).
- Fwd/Bwd Header Length = sum over the direction's packets of the parsed IP header (options and
  IPv6 extension headers included) plus the parsed L4 header (TCP data offset; 8 for UDP/ICMP).

Sequences (Arrow list columns, one element per packet in flow order): seq_time_s float64 (time
since the flow's first packet), seq_size int32 (frame length), seq_flags int16 (TCP flags, 0 for
non-TCP), seq_dir int8 (+1 forward, -1 backward).
"""

from __future__ import annotations

import numpy as np
import pandas as pd
import pyarrow as pa

from uavcas.schema import ACTIVITY_TIMEOUT_S, FEATURES

from .assemble import HOST_VIEWS, Flows
from .packets import PacketTable, addresses_to_str

FLAG_BITS: tuple[tuple[str, int], ...] = (
    ("FIN Flag Count", 0x01),
    ("SYN Flag Count", 0x02),
    ("RST Flag Count", 0x04),
    ("PSH Flag Count", 0x08),
    ("ACK Flag Count", 0x10),
    ("URG Flag Count", 0x20),
    ("CWE Flag Count", 0x80),
    ("ECE Flag Count", 0x40),
)
CSV_LEAD_COLUMNS: tuple[str, ...] = (
    "src_ip", "src_port", "dst_ip", "dst_port", "protocol", "packets", "bytes", "duration_s",
)  # fmt: skip


class _Stats:
    """count/sum/mean/std/min/max of values grouped by a non-decreasing group id in [0, n)."""

    def __init__(self, values: np.ndarray, group: np.ndarray, n: int):
        v = values.astype(np.float64)
        self.count = np.bincount(group, minlength=n).astype(np.float64)
        self.sum = np.bincount(group, weights=v, minlength=n)
        with np.errstate(invalid="ignore", divide="ignore"):
            self.mean = np.where(self.count > 0, self.sum / np.maximum(self.count, 1), 0.0)
            dev = np.bincount(group, weights=(v - self.mean[group]) ** 2, minlength=n)
            self.std = np.where(self.count > 1, np.sqrt(dev / np.maximum(self.count - 1, 1)), 0.0)
        self.max = np.zeros(n)
        self.min = np.zeros(n)
        if v.shape[0]:
            starts = np.flatnonzero(np.concatenate(([True], group[1:] != group[:-1])))
            present = group[starts]
            self.max[present] = np.maximum.reduceat(v, starts)
            self.min[present] = np.minimum.reduceat(v, starts)


def _gaps(t: np.ndarray, group: np.ndarray, n: int) -> _Stats:
    """Statistics of consecutive gaps within each group (t sorted within group)."""
    same = group[1:] == group[:-1]
    return _Stats(np.diff(t)[same], group[1:][same], n)


def _list_column(values: np.ndarray, starts: np.ndarray, pa_type: pa.DataType) -> pd.api.extensions.ExtensionArray:
    arr = pa.ListArray.from_arrays(pa.array(starts.astype(np.int32)), pa.array(values, type=pa_type))
    return pd.arrays.ArrowExtensionArray(arr)


def flow_frame(p: PacketTable, fl: Flows, sequences: bool = True) -> pd.DataFrame:
    """One row per flow: identity, counts, (optionally) sequences, then the 47 features."""
    n = fl.n_flows
    o, g, fwd, starts = fl.order, fl.flow, fl.fwd, fl.starts
    t = p["ts_s"][o]
    size = p["frame_len"][o].astype(np.float64)
    flags = p["tcp_flags"][o]
    hdr = p["ip_hdr_len"][o].astype(np.float64) + p["l4_hdr_len"][o]

    first_ts = t[starts[:-1]] if n else np.zeros(0)
    last_ts = t[starts[1:] - 1] if n else np.zeros(0)
    duration = last_ts - first_ts
    allp = _Stats(size, g, n)
    iat = _gaps(t, g, n)
    fw = _Stats(size[fwd], g[fwd], n)
    bw = _Stats(size[~fwd], g[~fwd], n)
    fiat = _gaps(t[fwd], g[fwd], n)
    biat = _gaps(t[~fwd], g[~fwd], n)

    same = g[1:] == g[:-1]
    gap = np.diff(t)
    idle_mask = same & (gap > ACTIVITY_TIMEOUT_S)
    idle = _Stats(gap[idle_mask], g[1:][idle_mask], n)
    with np.errstate(invalid="ignore", divide="ignore"):
        safe_dur = np.where(duration > 0, duration, 1.0)
        feats: dict[str, np.ndarray] = {
            "Flow Duration": duration,
            "Flow Bytes/s": np.where(duration > 0, allp.sum / safe_dur, 0.0),
            "Flow Packets/s": np.where(duration > 0, allp.count / safe_dur, 0.0),
            "Flow IAT Mean": iat.mean,
            "Flow IAT Std": iat.std,
            "Flow IAT Max": iat.max,
            "Flow IAT Min": iat.min,
            "Min Packet Length": allp.min,
            "Max Packet Length": allp.max,
            "Packet Length Mean": allp.mean,
            "Packet Length Std": allp.std,
            "Packet Length Variance": allp.std**2,
        }
        for name, bit in FLAG_BITS:
            feats[name] = np.bincount(g, weights=((flags & bit) != 0).astype(np.float64), minlength=n)
        feats["Down/Up Ratio"] = np.where(fw.count > 0, bw.count / np.maximum(fw.count, 1), 0.0)
        feats["Average Packet Size"] = allp.mean
        feats["Active Mean"] = (duration - idle.sum) / (1.0 + idle.count)
        feats["Idle Mean"] = idle.mean
        feats["Idle Max"] = idle.max
    feats.update(
        {
            "Total Fwd Packets": fw.count,
            "Total Backward Packets": bw.count,
            "Total Length of Fwd Packets": fw.sum,
            "Total Length of Bwd Packets": bw.sum,
            "Fwd Packet Length Max": fw.max,
            "Fwd Packet Length Min": fw.min,
            "Fwd Packet Length Mean": fw.mean,
            "Fwd Packet Length Std": fw.std,
            "Bwd Packet Length Max": bw.max,
            "Bwd Packet Length Min": bw.min,
            "Bwd Packet Length Mean": bw.mean,
            "Bwd Packet Length Std": bw.std,
            "Fwd IAT Total": fiat.sum,
            "Fwd IAT Mean": fiat.mean,
            "Fwd IAT Std": fiat.std,
            "Fwd IAT Max": fiat.max,
            "Bwd IAT Total": biat.sum,
            "Bwd IAT Mean": biat.mean,
            "Bwd IAT Std": biat.std,
            "Bwd IAT Max": biat.max,
            "Fwd Header Length": np.bincount(g[fwd], weights=hdr[fwd], minlength=n),
            "Bwd Header Length": np.bincount(g[~fwd], weights=hdr[~fwd], minlength=n),
        }
    )
    assert tuple(feats) == FEATURES

    # Identity: the forward endpoint is the first packet's source, or its destination when the
    # first packet travels backward (a SYN-ACK whose SYN was not captured).
    first = o[starts[:-1]] if n else np.zeros(0, dtype=np.int64)
    first_fwd = fwd[starts[:-1]] if n else np.zeros(0, dtype=bool)
    s_hi = np.where(first_fwd, p["src_hi"][first], p["dst_hi"][first])
    s_lo = np.where(first_fwd, p["src_lo"][first], p["dst_lo"][first])
    d_hi = np.where(first_fwd, p["dst_hi"][first], p["src_hi"][first])
    d_lo = np.where(first_fwd, p["dst_lo"][first], p["src_lo"][first])
    sport = np.where(first_fwd, p["sport"][first], p["dport"][first]).astype(np.int32)
    dport = np.where(first_fwd, p["dport"][first], p["sport"][first]).astype(np.int32)
    proto = p["proto"][first].astype(np.int16)
    if fl.config.view in HOST_VIEWS:  # ports and protocol are not part of a host-pair key
        sport, dport, proto = np.zeros_like(sport), np.zeros_like(dport), np.zeros_like(proto)
    cols: dict[str, object] = {
        "flow_id": np.arange(n, dtype=np.int64),
        "src_ip": addresses_to_str(s_hi, s_lo),
        "src_port": sport,
        "dst_ip": addresses_to_str(d_hi, d_lo),
        "dst_port": dport,
        "protocol": proto,
        "first_ts": first_ts,
        "last_ts": last_ts,
        "capture_point": np.asarray(p.points, dtype=object)[fl.point] if n else np.zeros(0, dtype=object),
        "packets": allp.count.astype(np.int64),
        "bytes": allp.sum.astype(np.int64),
        "duration_s": duration,
    }
    df = pd.DataFrame(cols)
    df["src_ip"] = df["src_ip"].astype(object)
    df["dst_ip"] = df["dst_ip"].astype(object)
    df["capture_point"] = df["capture_point"].astype(object)
    if sequences:
        df["seq_time_s"] = _list_column(t - first_ts[g] if n else t, starts, pa.float64())
        df["seq_size"] = _list_column(size.astype(np.int32), starts, pa.int32())
        df["seq_flags"] = _list_column(flags.astype(np.int16), starts, pa.int16())
        df["seq_dir"] = _list_column(np.where(fwd, 1, -1).astype(np.int8), starts, pa.int8())
    feat_df = pd.DataFrame({k: v.astype(np.float64) for k, v in feats.items()})
    return pd.concat([df, feat_df], axis=1)
