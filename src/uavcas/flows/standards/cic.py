"""Feature standard `cic` (the default): 47 columns exactly as CICFlowMeter computes them.

Source: CICFlowMeter-4.0 (github.com/ahlashkari/CICFlowMeter), `BasicFlow` (statistics),
`FlowGenerator` (flow termination, see `uavcas.flows.assemble` rule 4) and `PacketReader`
(per-packet fields). Units are CICFlowMeter's: times in MICROSECONDS (packet times truncated to
whole us, as jnetpcap's `timestampInMicros`), lengths in bytes, rates per second.

Per packet: payload = the TCP/UDP payload (IP total length - IP header - TCP data offset / 8),
header = the TCP header (data offset) or 8 for UDP; both 0 for other protocols, which
CICFlowMeter does not parse. Statistics are Apache commons-math `SummaryStatistics`: mean,
SAMPLE standard deviation and variance (n - 1; 0 for one value). Quirks kept on purpose, so the
values equal CICFlowMeter's:
- Min/Max Packet Length, Packet Length Mean/Std/Variance and Average Packet Size use
  `flowLengthStats`, to which `BasicFlow.firstPacket` adds the first packet's payload TWICE; the
  Average is that sum over the packet count.
- Flow IAT Mean/Std/Max/Min of a one-packet flow are NaN (no gap); Flow Bytes/s and Flow
  Packets/s of a zero-duration flow are inf (NaN when it carried 0 bytes): CICFlowMeter divides
  by the duration unguarded. (The IDS maps these to 0; `uavcas.ids.features`.)
- Down/Up Ratio = backward packets / forward packets in INTEGER division.
- Fwd/Bwd IAT * are 0 with fewer than 2 packets in the direction.
- Active/Idle (`updateActiveIdleTime`, activity timeout 5 s): a gap between consecutive packets
  longer than 5 s is an idle period (Idle Mean/Max); the stretch before it, if longer than 0, is
  an active period; the last active period is never recorded (`endActiveIdleTime` is not
  called), so a flow without an idle gap has Active Mean 0.
- CWE Flag Count counts CWR (0x80); ECE Flag Count counts ECE (0x40).
Deliberate differences: ICMP flows keep their IP protocol number (CICFlowMeter reports 0);
IPv6 times are in us too (CICFlowMeter 4.0 reads them in ms); later IP fragments belong to
their datagram's flow (CICFlowMeter cannot parse their transport header).
"""

from __future__ import annotations

import numpy as np

from ..groupstats import GroupStats, direction_stats, gaps, length_and_flag_stats
from ..packets import payload_and_header
from .base import FeatureStandard, FlowPackets
from .meanings import Wording, meanings
from .registry import register

# Direction-independent statistics over all packets of the flow ...
FLOW_FEATURES: tuple[str, ...] = (
    "Flow Duration", "Flow Bytes/s", "Flow Packets/s", "Flow IAT Mean", "Flow IAT Std", "Flow IAT Max",
    "Flow IAT Min", "Min Packet Length", "Max Packet Length", "Packet Length Mean", "Packet Length Std",
    "Packet Length Variance", "FIN Flag Count", "SYN Flag Count", "RST Flag Count", "PSH Flag Count",
    "ACK Flag Count", "URG Flag Count", "CWE Flag Count", "ECE Flag Count", "Down/Up Ratio",
    "Average Packet Size", "Active Mean", "Idle Mean", "Idle Max",
)  # fmt: skip
# ... then by direction. Forward = the initiator's direction (first packet; the SYN sender for TCP).
DIRECTION_FEATURES: tuple[str, ...] = (
    "Total Fwd Packets", "Total Backward Packets", "Total Length of Fwd Packets", "Total Length of Bwd Packets",
    "Fwd Packet Length Max", "Fwd Packet Length Min", "Fwd Packet Length Mean", "Fwd Packet Length Std",
    "Bwd Packet Length Max", "Bwd Packet Length Min", "Bwd Packet Length Mean", "Bwd Packet Length Std",
    "Fwd IAT Total", "Fwd IAT Mean", "Fwd IAT Std", "Fwd IAT Max", "Bwd IAT Total", "Bwd IAT Mean", "Bwd IAT Std",
    "Bwd IAT Max", "Fwd Header Length", "Bwd Header Length",
)  # fmt: skip
FEATURES: tuple[str, ...] = FLOW_FEATURES + DIRECTION_FEATURES
assert len(FLOW_FEATURES) == 25 and len(DIRECTION_FEATURES) == 22 and len(set(FEATURES)) == 47

ACTIVITY_TIMEOUT_US = 5_000_000  # CICFlowMeter's activityTimeout
# (name, TCP flag bit) in the order of FEATURES; CICFlowMeter's "CWE" is CWR.
FLAG_BITS: tuple[tuple[str, int], ...] = (
    ("FIN Flag Count", 0x01), ("SYN Flag Count", 0x02), ("RST Flag Count", 0x04), ("PSH Flag Count", 0x08),
    ("ACK Flag Count", 0x10), ("URG Flag Count", 0x20), ("CWE Flag Count", 0x80), ("ECE Flag Count", 0x40),
)  # fmt: skip
UNITS: dict[str, str] = {f: "count" for f in FEATURES}
UNITS.update({f: "us"
              for f in FEATURES if "IAT" in f or f in ("Flow Duration", "Active Mean", "Idle Mean", "Idle Max")})
UNITS.update({f: "bytes" for f in FEATURES if "Length" in f or f == "Average Packet Size"})
UNITS.update({"Flow Bytes/s": "bytes/s", "Flow Packets/s": "packets/s", "Down/Up Ratio": "ratio"})
UNITS.update({f: "packets" for f in ("Total Fwd Packets", "Total Backward Packets")})
UNITS["Packet Length Variance"] = "bytes^2"  # the square of the length's unit


def _active_idle(t: np.ndarray, g: np.ndarray, n: int) -> tuple[GroupStats, GroupStats]:
    gap, gg = gaps(t, g)
    idle_at = np.flatnonzero(gap > ACTIVITY_TIMEOUT_US)  # gap k lies between packets j-1 and j
    idle = GroupStats(gap[idle_at], gg[idle_at], n)
    if idle_at.shape[0] == 0:
        return GroupStats(np.zeros(0), np.zeros(0, dtype=np.int64), n), idle
    same = np.flatnonzero(g[1:] == g[:-1])  # packet index j = same[k] + 1 for gap k
    j = same[idle_at] + 1
    # an active period starts at the flow's first packet or right after an idle gap
    starts = np.concatenate(([True], g[1:] != g[:-1]))
    starts[j] = True
    start_pos = np.maximum.accumulate(np.where(starts, np.arange(t.shape[0]), 0))
    length = t[j - 1] - t[start_pos[j - 1]]
    pos = length > 0
    return GroupStats(length[pos], g[j][pos], n), idle


def cic_features(
    g: np.ndarray, fwd: np.ndarray, ts_ns: np.ndarray, payload: np.ndarray, header: np.ndarray,
    flags: np.ndarray, starts: np.ndarray,
) -> dict[str, np.ndarray]:  # fmt: skip
    """The 47 `cic` features of flows given packets in flow order (g non-decreasing)."""
    n = starts.shape[0] - 1
    t = ts_ns // 1000  # CICFlowMeter's integer microseconds
    first, last = starts[:-1], starts[1:] - 1
    dur = (t[last] - t[first]).astype(np.float64) if n else np.zeros(0)
    pl = payload.astype(np.float64)
    count = np.diff(starts).astype(np.float64)
    bwd = ~fwd
    fw = GroupStats(pl[fwd], g[fwd], n)
    bw = GroupStats(pl[bwd], g[bwd], n)
    # flowLengthStats: every payload plus the first packet's once more (BasicFlow.firstPacket)
    dg = np.concatenate([g, g[first]])
    o = np.argsort(dg, kind="stable")
    lens = GroupStats(np.concatenate([pl, pl[first]])[o], dg[o], n)
    iat_v, iat_g = gaps(t, g)
    iat = GroupStats(iat_v, iat_g, n, empty=np.nan)
    fi_v, fi_g = gaps(t[fwd], g[fwd])
    bi_v, bi_g = gaps(t[bwd], g[bwd])
    fiat, biat = GroupStats(fi_v, fi_g, n), GroupStats(bi_v, bi_g, n)
    active, idle = _active_idle(t, g, n)
    total = fw.sum + bw.sum
    with np.errstate(divide="ignore", invalid="ignore"):
        feats: dict[str, np.ndarray] = {
            "Flow Duration": dur,
            "Flow Bytes/s": total / (dur / 1e6),
            "Flow Packets/s": count / (dur / 1e6),
            "Flow IAT Mean": iat.mean,
            "Flow IAT Std": iat.std,
            "Flow IAT Max": iat.max,
            "Flow IAT Min": iat.min,
            **length_and_flag_stats(lens, g, flags, FLAG_BITS, n),
        }
        feats["Down/Up Ratio"] = np.where(fw.count > 0, np.floor(bw.count / np.maximum(fw.count, 1)), 0.0)
        feats["Average Packet Size"] = np.where(count > 0, lens.sum / np.maximum(count, 1), 0.0)
    feats["Active Mean"] = active.mean
    feats["Idle Mean"] = idle.mean
    feats["Idle Max"] = idle.max
    feats.update(
        {
            "Total Fwd Packets": fw.count,
            "Total Backward Packets": bw.count,
            "Total Length of Fwd Packets": fw.sum,
            "Total Length of Bwd Packets": bw.sum,
            "Fwd Header Length": np.bincount(g[fwd], weights=header[fwd].astype(np.float64), minlength=n),
            "Bwd Header Length": np.bincount(g[bwd], weights=header[bwd].astype(np.float64), minlength=n),
        }
    )
    feats.update(direction_stats(fw, bw, fiat, biat, iat_max=True))
    assert set(feats) == set(FEATURES), set(feats) ^ set(FEATURES)
    feats = {k: feats[k] for k in FEATURES}
    return feats


def compute(fp: FlowPackets) -> dict[str, np.ndarray]:
    fl = fp.flows
    payload, header = payload_and_header(fp.ordered("proto"), fp.ordered("ip_len"), fp.ordered("ip_hdr_len"),
                                         fp.ordered("l4_hdr_len"))
    return cic_features(fl.flow, fl.fwd, fp.ordered("ts_ns"), payload, header, fp.ordered("tcp_flags"), fl.starts)


STANDARD = register(FeatureStandard(
    name="cic",
    columns=FEATURES,
    units=UNITS,
    meanings=meanings(FEATURES, Wording(
        length="TCP/UDP payload length", forward="forward (initiator -> responder)",
        header="sum of the TCP/UDP header bytes of {who}", zero_duration="NaN or inf, as CICFlowMeter divides")),
    source="CICFlowMeter-4.0 BasicFlow/FlowGenerator",
    summary="CICFlowMeter's definitions, us",
    compute=compute,
    # cic lengths are payload bytes
    episode_summary={
        "Flow Duration": "flow_duration_us", "Total Fwd Packets": "fwd_packets",
        "Total Backward Packets": "bwd_packets",
        "Total Length of Fwd Packets": "fwd_payload_bytes", "Total Length of Bwd Packets": "bwd_payload_bytes",
        "Flow Bytes/s": "flow_payload_bytes_per_s", "Flow Packets/s": "flow_packets_per_s",
        "Flow IAT Mean": "flow_iat_mean_us", "Packet Length Mean": "payload_length_mean_bytes",
    },
))  # fmt: skip
