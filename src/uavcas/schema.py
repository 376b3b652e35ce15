"""Column contract of a uavcas dataset (`flows.parquet`), shared by extraction, labels, analysis, IDS.

It sits at the base of the package (below `flows/`, `labels/` and `dataset/`), next to the
vocabulary it derives the class and axis columns from.

Feature standards: a dataset's 47 feature columns follow ONE standard, named in its card
(`dataset.json: features`). The standards, with their columns, units and definitions, are the
registry `uavcas.flows.standards` (one module each: `cic`, CICFlowMeter-4.0's, the default, and
`paper`, the authors'); this module holds every other column. Several names occur in two
standards with different meanings (`Flow Duration` is us in cic, s in paper): never mix standards.
"""

from __future__ import annotations

from uavcas import vocabulary as _v

# 2: feature standards, first_ts_ns; 3: context columns (ctx_*); 4: provoked effect, provoked_packets; 5: families
# jamming, gps_spoof, mavlink_inject (their columns and effects), the card's column dictionary and fidelity_failed;
# 6: route context (ctx_route_lonely_frac, ctx_path_len_shift_max, ctx_delay_shift_max_ms; episodes ctx_pkt_*)
SCHEMA_VERSION = 6

# Context features (`ctx_*`): what switch monitors observe around a flow, computed from the run's
# captures at extraction time (`uavcas.flows.context`; definitions and what a deployed node must
# observe for each: docs/formats.md). Not part of a feature standard: the flow features stay the
# standard's 47, and models that use context (`uavcas.ids.baseline("context")`) add these.
CONTEXT_FLOW_FEATURES: tuple[str, ...] = (
    "ctx_path_len_mean", "ctx_delay_ms", "ctx_lost_frac", "ctx_offhome_frac", "ctx_ttl_off_frac",
    "ctx_ttl_levels", "ctx_neardup_frac", "ctx_retx_frac", "ctx_seq_regress_frac", "ctx_rtt_ms",
)  # fmt: skip
# per host and window ...
CONTEXT_HOST_METRICS: tuple[str, ...] = (
    "flow_share", "unanswered_frac", "rtt_ms", "delay_ms", "out_share", "lost_out_frac", "lost_in_frac",
    "offhome_frac", "ttl_off_frac", "path_len_mean",
)  # fmt: skip
# ... and against the median of the host's earlier windows (metric -> its shift)
CONTEXT_HOST_SHIFTS: dict[str, str] = {
    "log_flows": "flows_log_ratio", "unanswered_frac": "unanswered_shift", "rtt_ms": "rtt_shift_ms",
    "delay_ms": "delay_shift_ms", "out_share": "out_share_shift", "lost_out_frac": "lost_out_shift",
    "path_len_mean": "path_len_shift",
}  # fmt: skip
# for the flow's initiator (src) and responder (dst)
CONTEXT_HOST_FEATURES: tuple[str, ...] = tuple(
    f"ctx_{role}_{m}" for role in ("src", "dst") for m in CONTEXT_HOST_METRICS + tuple(CONTEXT_HOST_SHIFTS.values())
)
# per window for the flow's host pair, and against the pair's earlier windows
CONTEXT_PAIR_METRICS: tuple[str, ...] = ("flow_share", "unanswered_frac", "rtt_ms", "delay_ms", "lost_frac",
                                         "path_len_mean")
CONTEXT_PAIR_SHIFTS: dict[str, str] = {
    "unanswered_frac": "unanswered_shift", "rtt_ms": "rtt_shift_ms", "delay_ms": "delay_shift_ms",
    "path_len_mean": "path_len_shift",
}  # fmt: skip
CONTEXT_PAIR_FEATURES: tuple[str, ...] = tuple(
    f"ctx_pair_{m}" for m in CONTEXT_PAIR_METRICS + tuple(CONTEXT_PAIR_SHIFTS.values())
)
# the flow's own round trip, delay and path length less the median of its pair's earlier windows
CONTEXT_FLOW_SHIFTS: tuple[str, ...] = ("ctx_rtt_shift_ms", "ctx_delay_shift_ms", "ctx_path_len_shift")
CONTEXT_NET_FEATURES: tuple[str, ...] = ("ctx_net_lost_frac", "ctx_net_path_len_mean", "ctx_net_unanswered_frac")
# every window the flow's packets crossed, each packet against its directed pair's earlier windows
# (`flows.routes`): what a wormhole does to a long stream that began before it
CONTEXT_ROUTE_FEATURES: tuple[str, ...] = ("ctx_route_lonely_frac", "ctx_path_len_shift_max", "ctx_delay_shift_max_ms")
CONTEXT_FEATURES: tuple[str, ...] = (
    CONTEXT_FLOW_FEATURES + CONTEXT_HOST_FEATURES + CONTEXT_PAIR_FEATURES + CONTEXT_FLOW_SHIFTS + CONTEXT_NET_FEATURES
    + CONTEXT_ROUTE_FEATURES
)
CONTEXT_PREFIX = "ctx_"
assert len(set(CONTEXT_FEATURES)) == len(CONTEXT_FEATURES) == 63
assert all(c.startswith(CONTEXT_PREFIX) for c in CONTEXT_FEATURES)

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
    "first_ts",  # float64 Unix s of the first packet (convenience; rounded to ~0.2 us)
    "last_ts",
    "first_ts_ns",  # int64 Unix ns of the first packet: exact; packet times = this + seq_time_s
    "capture_point",
)
COUNT_COLUMNS: tuple[str, ...] = ("packets", "bytes", "duration_s")
SEQUENCE_COLUMNS: tuple[str, ...] = ("seq_time_s", "seq_size", "seq_flags", "seq_dir", "seq_effect")
EFFECTS, ATTACK_EFFECTS = _v.EFFECTS, _v.ATTACK_EFFECTS
# Per-flow ground truth from the packets' effects (labels/effects.py): attack_fraction is exactly
# attack_packets / packets; provoked_packets are the attack packets whose effect is `provoked`;
# attack_packets_<family> split attack_packets by family.
TRUTH_COLUMNS: tuple[str, ...] = ("attack_packets", "attack_fraction", "provoked_packets") + _v.ATTACK_PACKET_COLUMNS
META_LABEL_COLUMNS: tuple[str, ...] = TRUTH_COLUMNS + LABEL_COLUMNS + ("label", "label_source")
METADATA_COLUMNS: tuple[str, ...] = ID_COLUMNS + AXIS_COLUMNS + META_LABEL_COLUMNS

# ---------------------------------------------------------------------------------------------
# The episode view (`window-host`, `uavcas.labels.episodes`): one row per plan node per plan
# window, the unit in which a collaborative attack (two families on one victim) is visible. Its
# rows are no flows: they have their own identity columns and features, all with units in their
# names, and the same truth and label columns as flows (attack_packets, label_<family>, label).
EPISODE_VIEW = "window-host"
EPISODE_ID_COLUMNS: tuple[str, ...] = (
    "run_id", "config", "seed", "view", "host", "host_ip", "window", "first_ts", "last_ts", "first_ts_ns",
)  # fmt: skip
# The host's own packets in the window (sent: it is the source; received: the destination).
EPISODE_PACKET_UNITS: dict[str, str] = {
    "packets_out": "packets", "packets_in": "packets", "bytes_out": "bytes", "bytes_in": "bytes",
    "packets_per_s": "packets/s", "bytes_per_s": "bytes/s", "active_s": "s",
    "peers": "hosts", "peer_ports": "ports",
    "syn_out": "packets", "syn_in": "packets", "synack_out": "packets", "synack_in": "packets",
    "rst_out": "packets", "rst_in": "packets", "fin_out": "packets", "fin_in": "packets",
    "udp_share": "ratio", "icmp_share": "ratio",
    "flows": "flows", "flows_out": "flows", "flows_in": "flows",
}  # fmt: skip
# Each standard summarises a subset of its flow features per episode (`FeatureStandard.
# episode_summary`: feature -> column stem with its unit), as <stem>_mean and <stem>_max over the
# 5-tuple flows that start in the window and have the host as an endpoint.
EPISODE_STATS: tuple[str, ...] = ("mean", "max")

# the flows' context columns summarised per episode (mean and max over the same flows)
# the same route measures over the episode's own packets (`flows.routes`), whichever flow they belong to
EPISODE_ROUTE_FEATURES: tuple[str, ...] = (
    "ctx_pkt_route_lonely_frac", "ctx_pkt_path_len_shift", "ctx_pkt_delay_shift_ms", "ctx_pkt_route_lonely_max",
    "ctx_pkt_path_len_shift_peer_max", "ctx_pkt_delay_shift_peer_max_ms", "ctx_pkt_off_own_route_frac",
    "ctx_pkt_off_own_route_max", "ctx_pkt_passing_off_route_frac", "ctx_pkt_passing_off_route_max",
    "ctx_pkt_lonely_off_route_frac", "ctx_pkt_lonely_off_route_max")
EPISODE_CONTEXT_FEATURES: tuple[str, ...] = tuple(
    f"{c}_{s}" for c in CONTEXT_FEATURES for s in EPISODE_STATS) + EPISODE_ROUTE_FEATURES
EPISODE_COUNT_COLUMNS: tuple[str, ...] = ("packets",)  # the host's packets in the window (truth's denominator)
EPISODE_METADATA_COLUMNS: tuple[str, ...] = (
    EPISODE_ID_COLUMNS + AXIS_COLUMNS + EPISODE_COUNT_COLUMNS + META_LABEL_COLUMNS
)
