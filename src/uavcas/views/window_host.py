"""The `window-host` view: one row per plan node per plan window, an episode (`uavcas.labels.episodes`:
its features, truth and labels, from the same packets and effects as the 5-tuple flows). The unit
in which a collaborative attack (two families on one victim) is visible.
"""

from __future__ import annotations

import pandas as pd
import pyarrow as pa

from uavcas.dataset.dictionary import NO_UNIT, context_entry, feature_entry
from uavcas.flows.standards import episode_feature_columns
from uavcas.flows.standards import standard as feature_standard
from uavcas.labels.episodes import episode_rule_text, host_window_frame
from uavcas.schema import (
    CONTEXT_FEATURES,
    EPISODE_CONTEXT_FEATURES,
    EPISODE_ID_COLUMNS,
    EPISODE_METADATA_COLUMNS,
    EPISODE_PACKET_UNITS,
    EPISODE_ROUTE_FEATURES,
    EPISODE_STATS,
    EPISODE_VIEW,
)

from .base import IDENTITY_TYPES, RowNoun, ViewInput, ViewRows, ViewSpec, axis_fields, label_fields
from .registry import register

NAME = EPISODE_VIEW
_ID_TYPES = {**IDENTITY_TYPES, "host": pa.string(), "host_ip": pa.string(), "window": pa.int64()}
# counts of packets, bytes, peers, ports and flows are integers; rates, shares, spans and summaries floats
_INT_UNITS = ("packets", "bytes", "hosts", "ports", "flows")
_IDS: dict[str, tuple[str, str]] = {
    "host": (NO_UNIT, "the plan node (UAV or base station) the episode is about"),
    "host_ip": (NO_UNIT, "the node's address"),
    "window": (NO_UNIT, "plan window index: floor((t - t0) / window_s)"),
}
# the packet features (schema.EPISODE_PACKET_UNITS gives their units)
_PACKETS: dict[str, str] = {
    "packets_out": "packets the node sent in the window", "packets_in": "packets the node received",
    "bytes_out": "frame bytes the node sent", "bytes_in": "frame bytes the node received",
    "packets_per_s": "packets sent or received per second of window", "bytes_per_s": "frame bytes per second of window",
    "active_s": "last packet time - first packet time in the window", "peers": "distinct addresses at the other end",
    "peer_ports": "distinct TCP/UDP ports at the other end", "syn_out": "TCP SYNs (ACK clear) sent",
    "syn_in": "TCP SYNs (ACK clear) received", "synack_out": "TCP SYN-ACKs sent", "synack_in": "TCP SYN-ACKs received",
    "rst_out": "TCP RSTs sent", "rst_in": "TCP RSTs received", "fin_out": "TCP FINs sent",
    "fin_in": "TCP FINs received",
    "udp_share": "share of the episode's packets that are UDP", "icmp_share": "share that are ICMP (or ICMPv6)",
    "flows": "5-tuple flows starting in the window with the node as an endpoint",
    "flows_out": "of those, initiated by the node", "flows_in": "of those, initiated by its peer",
}  # fmt: skip
SHOWN_FEATURES = ("packets_per_s", "bytes_per_s", "peers", "syn_in", "synack_out", "flows_in")


def fields(standard: str, context: bool) -> list[pa.Field]:
    """The columns of a window-host shard: identity, axes, packets, the episode features
    (`FeatureStandard.episode_columns`), the summarised context columns when `context`, then the
    same truth and label columns as flows."""
    out = [pa.field(c, _ID_TYPES[c]) for c in EPISODE_ID_COLUMNS] + axis_fields()
    out += [pa.field("packets", pa.int64())]
    out += [pa.field(c, pa.int64() if EPISODE_PACKET_UNITS.get(c) in _INT_UNITS else pa.float64())
            for c in episode_feature_columns(standard)]
    out += [pa.field(c, pa.float64()) for c in (EPISODE_CONTEXT_FEATURES if context else ())]
    return out + label_fields()


def describe(name: str, standard: str) -> tuple[str, str] | None:
    """The episode's identity, packet features, route columns and the summaries of its flows'
    features and context columns."""
    if name in _IDS:
        return _IDS[name]
    if name in _PACKETS:
        return EPISODE_PACKET_UNITS[name], _PACKETS[name]
    if name in EPISODE_ROUTE_FEATURES:
        return context_entry(name)
    stem, _, stat = name.rpartition("_")
    if stat not in EPISODE_STATS:
        return None
    word = "mean" if stat == "mean" else "largest"
    for feat, feat_stem in feature_standard(standard).episode_summary.items():
        if feat_stem == stem:
            unit, _ = feature_entry(feat, standard)  # type: ignore[misc]
            return unit, (f"{word} of the flows' {feat} [{standard}] over the flows starting in the window with the "
                          "node as an endpoint")
    ctx = context_entry(stem)
    if ctx is not None:
        return ctx[0], f"{word} of {stem} over those flows ({ctx[1]})"
    return None


def feature_card(standard: str) -> dict:
    """The card's record: packet counts and the mean / max of a subset of the standard's flow
    features (units of those features)."""
    std = feature_standard(standard)
    return {"standard": std.name,
            "source": f"{NAME} episodes (uavcas.labels.episodes) of flows by {std.source} ({std.module})",
            "summarised": {stem: feat for feat, stem in std.episode_summary.items()}, "units": std.episode_units}


def rows(inp: ViewInput) -> ViewRows:
    """The 5-tuple flows (with their context columns) per node and window, labelled from the
    packets' effects (`uavcas.labels.episodes`)."""
    ff = inp.frame.reset_index(drop=True)
    if inp.context is not None:
        ff = pd.concat([ff, pd.DataFrame(inp.context.to_numpy(), columns=list(CONTEXT_FEATURES))], axis=1)
    df = host_window_frame(inp.packets, inp.flows, ff, inp.truth, inp.plan, inp.t0_unix, standard=inp.standard,
                           routes=inp.routes)
    return ViewRows(df, 0, episode_rule_text())


VIEW = register(ViewSpec(
    name=NAME, row=RowNoun("host-window row", "host-window rows"), unit="host-window",
    meaning="one plan node's traffic in one plan window",
    card_rows="one per plan node per plan window (window-host episodes)", record_set="host_windows",
    help="one row per plan node per plan window (an episode: collaborative classes)",
    key_columns=("host", "window"), flow_key="5tuple", flow_labels=False, fields=fields,
    feature_columns=episode_feature_columns, context_columns=EPISODE_CONTEXT_FEATURES,
    metadata_columns=EPISODE_METADATA_COLUMNS, describe=describe, feature_card=feature_card,
    shown_features=SHOWN_FEATURES, report_title="Host-window features per class", rows=rows,
))
