"""Feature standard `paper`: the authors' 47 features (`PAPER_FEATURES`) as their generator computes
them.

Source: Sripathm2/Collaborative-UAV-Dataset, `Scripts/6-build_stat_csv.py` (`compute_features`),
fed by `Network-simulator/process_csvs.py` (tshark fields per packet: frame.time_epoch, frame.len,
tcp.flags). Per packet: time in float seconds since the epoch, size = frame length (bytes on the
wire, link header included), TCP flags (0 for UDP), direction 0 when the sender is the
STRING-smaller address of the pair (Python `sorted` of the two dotted strings, so '10.0.0.10' <
'10.0.0.2'), 1 otherwise; "Fwd" means direction 0.

Definitions (units: seconds, bytes, per second):
- Flow Duration = last - first time; Flow Bytes/s, Flow Packets/s, Fwd/Bwd Packets/s = total /
  duration, 0.0 when the duration is 0.
- Flow IAT Total/Mean/Std/Max/Min over the n - 1 gaps; Fwd/Bwd IAT Total/Mean/Std over the gaps of
  the direction's packets (0 with fewer than 2 packets in it). No IAT Max per direction.
- Standard deviations and the variance are POPULATION ones (numpy's default, ddof 0).
- Min/Max Packet Length are integers; Fwd/Bwd Packet Length Max/Min/Mean/Std floats, 0.0 for an
  empty direction.
- Flag counts: FIN 0x01, SYN 0x02, RST 0x04, PSH 0x08, ACK 0x10, URG 0x20, and, as their code
  has it, "CWE Flag Count" = 0x40 (the ECE bit) and "ECE Flag Count" = 0x80 (the CWR bit).
- Header Length = 20 x packets; Fwd/Bwd Header Length = 20 x the direction's packets (a fixed IP
  header size, whatever the packets carry).
- Average Packet Size = total length / packets.
Their generator writes no row for a flow under 2 packets: such flows get NaN here.
`INT_FEATURES` are written as integers in their CSV (`uavcas.dataset.uavcas_csv`).
"""

from __future__ import annotations

import numpy as np

from ..groupstats import GroupStats, direction_stats, gaps, length_and_flag_stats
from ..packets import ns_to_s
from .base import FeatureStandard, FlowPackets
from .meanings import Wording, meanings
from .registry import register

# The authors' 47 (Scripts/6-build_stat_csv.py FEATURE_NAMES): 25 flow-level, then 22 by direction.
PAPER_FEATURES: tuple[str, ...] = (
    "Flow Duration", "Total Packets", "Total Length of Packets", "Flow Bytes/s", "Flow Packets/s",
    "Flow IAT Total", "Flow IAT Mean", "Flow IAT Std", "Flow IAT Max", "Flow IAT Min",
    "Min Packet Length", "Max Packet Length", "Packet Length Mean", "Packet Length Std",
    "Packet Length Variance", "FIN Flag Count", "SYN Flag Count", "RST Flag Count", "PSH Flag Count",
    "ACK Flag Count", "URG Flag Count", "CWE Flag Count", "ECE Flag Count", "Header Length",
    "Average Packet Size",
    "Total Fwd Packets", "Total Bwd Packets", "Total Length of Fwd Packets", "Total Length of Bwd Packets",
    "Fwd Packets/s", "Bwd Packets/s", "Fwd Packet Length Max", "Fwd Packet Length Min",
    "Fwd Packet Length Mean", "Fwd Packet Length Std", "Bwd Packet Length Max", "Bwd Packet Length Min",
    "Bwd Packet Length Mean", "Bwd Packet Length Std", "Fwd IAT Total", "Fwd IAT Mean", "Fwd IAT Std",
    "Bwd IAT Total", "Bwd IAT Mean", "Bwd IAT Std", "Fwd Header Length", "Bwd Header Length",
)  # fmt: skip
assert len(PAPER_FEATURES) == 47 and len(set(PAPER_FEATURES)) == 47

FLAG_BITS: tuple[tuple[str, int], ...] = (
    ("FIN Flag Count", 0x01), ("SYN Flag Count", 0x02), ("RST Flag Count", 0x04), ("PSH Flag Count", 0x08),
    ("ACK Flag Count", 0x10), ("URG Flag Count", 0x20), ("CWE Flag Count", 0x40), ("ECE Flag Count", 0x80),
)  # fmt: skip
HEADER_BYTES = 20
INT_FEATURES: frozenset[str] = frozenset(
    ("Total Packets", "Total Length of Packets", "Min Packet Length", "Max Packet Length", "Header Length",
     "Total Fwd Packets", "Total Bwd Packets", "Total Length of Fwd Packets", "Total Length of Bwd Packets",
     "Fwd Header Length", "Bwd Header Length") + tuple(name for name, _ in FLAG_BITS)
)  # fmt: skip
UNITS: dict[str, str] = {f: "count" for f in PAPER_FEATURES}
UNITS.update({f: "s" for f in PAPER_FEATURES if "IAT" in f or f == "Flow Duration"})
UNITS.update({f: "bytes" for f in PAPER_FEATURES if "Length" in f or f == "Average Packet Size"})
UNITS.update({f: "packets/s" for f in PAPER_FEATURES if f.endswith("Packets/s")})
UNITS.update({"Flow Bytes/s": "bytes/s", "Total Packets": "packets", "Total Fwd Packets": "packets",
              "Total Bwd Packets": "packets"})
UNITS["Packet Length Variance"] = "bytes^2"  # the square of the length's unit


def paper_features(
    g: np.ndarray, dir0: np.ndarray, t_s: np.ndarray, size: np.ndarray, flags: np.ndarray, starts: np.ndarray
) -> dict[str, np.ndarray]:
    """The authors' 47 features of flows given packets in flow order (g non-decreasing)."""
    n = starts.shape[0] - 1
    count = np.diff(starts).astype(np.float64)
    first, last = starts[:-1], starts[1:] - 1
    dur = (t_s[last] - t_s[first]) if n else np.zeros(0)
    sz = size.astype(np.float64)
    allp = GroupStats(sz, g, n, ddof=0)
    iat_v, iat_g = gaps(t_s, g)
    iat = GroupStats(iat_v, iat_g, n, ddof=0)
    f, b = dir0, ~dir0
    fw, bw = GroupStats(sz[f], g[f], n, ddof=0), GroupStats(sz[b], g[b], n, ddof=0)
    fi_v, fi_g = gaps(t_s[f], g[f])
    bi_v, bi_g = gaps(t_s[b], g[b])
    fiat, biat = GroupStats(fi_v, fi_g, n, ddof=0), GroupStats(bi_v, bi_g, n, ddof=0)
    pos = dur > 0
    safe = np.where(pos, dur, 1.0)

    def rate(x: np.ndarray) -> np.ndarray:
        return np.where(pos, x / safe, 0.0)

    feats: dict[str, np.ndarray] = {
        "Flow Duration": dur,
        "Total Packets": count,
        "Total Length of Packets": allp.sum,
        "Flow Bytes/s": rate(allp.sum),
        "Flow Packets/s": rate(count),
        "Flow IAT Total": iat.sum,
        "Flow IAT Mean": iat.mean,
        "Flow IAT Std": iat.std,
        "Flow IAT Max": iat.max,
        "Flow IAT Min": iat.min,
        **length_and_flag_stats(allp, g, flags, FLAG_BITS, n),
    }
    feats["Header Length"] = HEADER_BYTES * count
    feats["Average Packet Size"] = allp.sum / np.maximum(count, 1)
    feats.update(
        {
            "Total Fwd Packets": fw.count,
            "Total Bwd Packets": bw.count,
            "Total Length of Fwd Packets": fw.sum,
            "Total Length of Bwd Packets": bw.sum,
            "Fwd Packets/s": rate(fw.count),
            "Bwd Packets/s": rate(bw.count),
            "Fwd Header Length": HEADER_BYTES * fw.count,
            "Bwd Header Length": HEADER_BYTES * bw.count,
        }
    )
    feats.update(direction_stats(fw, bw, fiat, biat, iat_max=False))
    assert set(feats) == set(PAPER_FEATURES), set(feats) ^ set(PAPER_FEATURES)
    feats = {k: feats[k] for k in PAPER_FEATURES}
    short = count < 2
    if short.any():
        feats = {k: np.where(short, np.nan, v) for k, v in feats.items()}
    return feats


def string_smaller(src: np.ndarray, dst: np.ndarray) -> np.ndarray:
    """Per flow: is the src address's text <= the dst's (the authors' direction-0 convention)?"""
    return np.asarray([a <= b for a, b in zip(src.tolist(), dst.tolist())], dtype=bool)


def compute(fp: FlowPackets) -> dict[str, np.ndarray]:
    fl = fp.flows
    smaller = string_smaller(fp.src_ip, fp.dst_ip) if fl.n_flows else np.zeros(0, dtype=bool)
    return paper_features(fl.flow, fl.fwd == smaller[fl.flow], ns_to_s(fp.ordered("ts_ns")), fp.ordered("frame_len"),
                          fp.ordered("tcp_flags"), fl.starts)


STANDARD = register(FeatureStandard(
    name="paper",
    columns=PAPER_FEATURES,
    units=UNITS,
    meanings=meanings(PAPER_FEATURES, Wording(
        length="frame length", forward="forward (sent by the string-smaller address)",
        header="20 bytes x the number of {who}", zero_duration="0", cwe_flag="ECE", ece_flag="CWR")),
    source="Sripathm2/Collaborative-UAV-Dataset Scripts/6-build_stat_csv.py",
    summary="the authors' 47, s",
    compute=compute,
    # paper lengths are frame bytes
    episode_summary={
        "Flow Duration": "flow_duration_s", "Total Fwd Packets": "fwd_packets", "Total Bwd Packets": "bwd_packets",
        "Total Length of Fwd Packets": "fwd_frame_bytes", "Total Length of Bwd Packets": "bwd_frame_bytes",
        "Flow Bytes/s": "flow_frame_bytes_per_s", "Flow Packets/s": "flow_packets_per_s",
        "Flow IAT Mean": "flow_iat_mean_s", "Packet Length Mean": "frame_length_mean_bytes",
    },
))  # fmt: skip
