"""Column contract of a uavcas dataset (`flows.parquet`), shared by extraction, labels, analysis, IDS.

It sits at the base of the package (below `flows/`, `labels/` and `dataset/`), next to the
vocabulary it derives the class and axis columns from.

The 47 flow statistics carry CICFlowMeter names so they can be compared with CICIDS-style data.
Units: times in seconds, sizes in bytes (link-layer frame length, as tshark's frame.len), rates per
second. The split "flow-level 25 / direction-aware 22" follows the paper's feature description.
"""

from __future__ import annotations

from uavcas import vocabulary as _v

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

# The vocabulary's words, re-exported: the dataset's class and label columns derive from them.
BENIGN, CLASSES, FAMILIES, FAMILY_CLASS, PAIRS = _v.BENIGN, _v.CLASSES, _v.FAMILIES, _v.FAMILY_CLASS, _v.PAIRS
LABEL_COLUMNS, class_name = _v.LABEL_COLUMNS, _v.class_name

# Per-flow identity and provenance columns. Never features (the IDS refuses them).
AXIS_COLUMNS: tuple[str, ...] = _v.AXIS_COLUMNS
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
SEQUENCE_COLUMNS: tuple[str, ...] = ("seq_time_s", "seq_size", "seq_flags", "seq_dir", "seq_effect")
EFFECTS, ATTACK_EFFECTS = _v.EFFECTS, _v.ATTACK_EFFECTS
# Per-flow ground truth from the packets' effects (labels/effects.py): attack_fraction is exactly
# attack_packets / packets; attack_packets_<family> split attack_packets by family.
TRUTH_COLUMNS: tuple[str, ...] = ("attack_packets", "attack_fraction") + _v.ATTACK_PACKET_COLUMNS
META_LABEL_COLUMNS: tuple[str, ...] = TRUTH_COLUMNS + LABEL_COLUMNS + ("label", "label_source")
METADATA_COLUMNS: tuple[str, ...] = ID_COLUMNS + AXIS_COLUMNS + META_LABEL_COLUMNS
