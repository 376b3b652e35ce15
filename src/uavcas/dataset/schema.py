"""Column contract of a uavcas dataset (`flows.parquet`), shared by extraction, labels, analysis, IDS.

The 47 flow statistics carry CICFlowMeter names so they can be compared with CICIDS-style data.
Units: times in seconds, sizes in bytes (link-layer frame length, as tshark's frame.len), rates per
second. The split "flow-level 25 / direction-aware 22" follows the paper's feature description.
"""

from __future__ import annotations

SCHEMA_VERSION = 1

# Direction-independent statistics over all packets of the flow.
FLOW_FEATURES: tuple[str, ...] = (
    "Flow Duration",
    "Flow Bytes/s",
    "Flow Packets/s",
    "Flow IAT Mean",
    "Flow IAT Std",
    "Flow IAT Max",
    "Flow IAT Min",
    "Min Packet Length",
    "Max Packet Length",
    "Packet Length Mean",
    "Packet Length Std",
    "Packet Length Variance",
    "FIN Flag Count",
    "SYN Flag Count",
    "RST Flag Count",
    "PSH Flag Count",
    "ACK Flag Count",
    "URG Flag Count",
    "CWE Flag Count",
    "ECE Flag Count",
    "Down/Up Ratio",
    "Average Packet Size",
    "Active Mean",
    "Idle Mean",
    "Idle Max",
)

# Forward = the initiator's direction (first packet; the SYN sender for TCP).
DIRECTION_FEATURES: tuple[str, ...] = (
    "Total Fwd Packets",
    "Total Backward Packets",
    "Total Length of Fwd Packets",
    "Total Length of Bwd Packets",
    "Fwd Packet Length Max",
    "Fwd Packet Length Min",
    "Fwd Packet Length Mean",
    "Fwd Packet Length Std",
    "Bwd Packet Length Max",
    "Bwd Packet Length Min",
    "Bwd Packet Length Mean",
    "Bwd Packet Length Std",
    "Fwd IAT Total",
    "Fwd IAT Mean",
    "Fwd IAT Std",
    "Fwd IAT Max",
    "Bwd IAT Total",
    "Bwd IAT Mean",
    "Bwd IAT Std",
    "Bwd IAT Max",
    "Fwd Header Length",
    "Bwd Header Length",
)

FEATURES: tuple[str, ...] = FLOW_FEATURES + DIRECTION_FEATURES
assert len(FLOW_FEATURES) == 25 and len(DIRECTION_FEATURES) == 22 and len(set(FEATURES)) == 47

# Idle/active split of CICFlowMeter: a gap longer than this ends an active period.
ACTIVITY_TIMEOUT_S = 5.0

# Attack families in canonical (alphabetical) order; class strings of pairs join in this order,
# which is also the order of the paper's composition names (Blackhole+DoS, DDoS+Replay, ...).
FAMILIES: tuple[str, ...] = ("blackhole", "ddos", "dos", "replay", "wormhole")
FAMILY_CLASS: dict[str, str] = {
    "blackhole": "Blackhole",
    "ddos": "DDoS",
    "dos": "DoS",
    "replay": "Replay",
    "wormhole": "Wormhole",
}
BENIGN = "Benign"
LABEL_COLUMNS: tuple[str, ...] = tuple(f"label_{f}" for f in FAMILIES)


def class_name(families: set[str] | list[str] | tuple[str, ...]) -> str:
    """Canonical class string of a set of families: 'Benign', 'DoS', 'Blackhole+DoS', ..."""
    fams = set(families)
    unknown = fams - set(FAMILIES)
    if unknown:
        raise ValueError(f"unknown attack family {sorted(unknown)}; known: {list(FAMILIES)}")
    if not fams:
        return BENIGN
    return "+".join(FAMILY_CLASS[f] for f in FAMILIES if f in fams)


# The 15 classes of the paper: Benign, 5 singles, 9 complementary pairs.
PAIRS: tuple[tuple[str, str], ...] = (
    ("blackhole", "dos"),
    ("blackhole", "ddos"),
    ("dos", "wormhole"),
    ("ddos", "wormhole"),
    ("blackhole", "wormhole"),
    ("blackhole", "replay"),
    ("ddos", "replay"),
    ("dos", "replay"),
    ("replay", "wormhole"),
)
CLASSES: tuple[str, ...] = (
    (BENIGN,) + tuple(FAMILY_CLASS[f] for f in FAMILIES) + tuple(class_name(p) for p in PAIRS)
)
assert len(CLASSES) == 15

# Per-flow identity and provenance columns. Never features (the IDS refuses them).
AXIS_COLUMNS: tuple[str, ...] = (
    "attacks",
    "n_uav",
    "n_bs",
    "payload",
    "pathloss",
    "modulation",
    "mission",
    "tx_dbm",
    "noise_dbm",
)
ID_COLUMNS: tuple[str, ...] = (
    "run_id",
    "config",
    "seed",
    "view",
    "flow_id",
    "src_ip",
    "src_port",
    "dst_ip",
    "dst_port",
    "protocol",
    "first_ts",
    "last_ts",
    "capture_point",
)
COUNT_COLUMNS: tuple[str, ...] = ("packets", "bytes", "duration_s")
SEQUENCE_COLUMNS: tuple[str, ...] = ("seq_time_s", "seq_size", "seq_flags", "seq_dir")
META_LABEL_COLUMNS: tuple[str, ...] = LABEL_COLUMNS + ("label", "label_source")
METADATA_COLUMNS: tuple[str, ...] = ID_COLUMNS + AXIS_COLUMNS + META_LABEL_COLUMNS
