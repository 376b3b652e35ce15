"""The data dictionary: every column a uavcas dataset can hold, with its Arrow dtype, its unit and a
one-line meaning, in one registry.

Everything that describes columns reads it: the card (`dataset.json: columns`, `store.rebuild`),
the Parquet field metadata (`field_metadata`, set by `uavcas.dataset.parquet`), the generated
section of docs/formats.md (`markdown`; a test keeps the file equal to it) and
`uavcas info DATASET --columns`. Feature units and meanings are those of the feature standard's
record (`uavcas.flows.standards`: `FeatureStandard.units`, `.meanings`); family columns
(`attack_packets_<family>`, `label_<family>`) and effect words derive from `uavcas.vocabulary`, so
a new standard, family or effect is described without an edit here. The columns only one view has
(the window-host view's `host`, its packet features and summaries) are described by the view's
module (`uavcas.views`: `ViewSpec.describe`), from the shared entries here (`feature_entry`,
`context_entry`). A column with no entry raises
`DictionaryError` (a test extracts datasets and looks every column up).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

from uavcas import vocabulary as v
from uavcas.channel.pathloss import names as pathloss_names
from uavcas.flows.standards import standard as feature_standard
from uavcas.traffic.payloads import PAYLOAD_NAMES

if TYPE_CHECKING:  # a view's modules read this dictionary's shared entries: the spec is passed in
    from uavcas.views.base import ViewSpec

NO_UNIT = "-"


class DictionaryError(ValueError):
    """A column the dictionary does not describe."""


@dataclass(frozen=True)
class Column:
    name: str
    dtype: str  # the Arrow type of flows.parquet, as pyarrow prints it
    unit: str  # NO_UNIT for names, flags and labels
    meaning: str


_IDS: dict[str, tuple[str, str]] = {
    "run_id": (NO_UNIT, "the run the row comes from (a campaign's manifest index)"),
    "config": (NO_UNIT, "the run's scenario string, canonical form"),
    "seed": (NO_UNIT, "the seed the run's plan was made with"),
    "view": (NO_UNIT, "how packets were grouped into rows: 5tuple, hostpair, window-hostpair or window-host"),
    "flow_id": (NO_UNIT, "0..n-1 within a run, in order of the flows' first packets"),
    "src_ip": (NO_UNIT, "the initiator's address (sender of the first packet; of the SYN for TCP)"),
    "src_port": (NO_UNIT, "the initiator's TCP/UDP port (0 in the host-pair views)"),
    "dst_ip": (NO_UNIT, "the responder's address"),
    "dst_port": (NO_UNIT, "the responder's TCP/UDP port (0 in the host-pair views)"),
    "protocol": (NO_UNIT, "IP protocol number: 6 TCP, 17 UDP, 1 ICMP (0 in the host-pair views)"),
    "first_ts": ("s", "Unix time of the first packet (float64: rounded to about 0.2 us)"),
    "last_ts": ("s", "Unix time of the last packet (float64: rounded to about 0.2 us)"),
    "first_ts_ns": ("ns", "Unix time of the first packet, exact; packet k is at first_ts_ns + seq_time_s[k] x 1e9"),
    "capture_point": (NO_UNIT, "the flow's vantage switch (s-<node>): its capture holds the row's packets, except a "
                      "transmission that never crossed it, kept at its last switch"),
}
_AXES: dict[str, tuple[str, str]] = {
    "attacks": (NO_UNIT, "the scenario's attacks field: family tokens with their parameters, or benign"),
    "n_uav": ("UAVs", "UAVs in the swarm"),
    "n_bs": ("base stations", "base stations (ground control) of the swarm"),
    "payload": (NO_UNIT, f"the benign traffic: one of {', '.join(PAYLOAD_NAMES)}"),
    "pathloss": (NO_UNIT, f"the air-to-ground path-loss model: one of {', '.join(pathloss_names())}"),
    "modulation": (NO_UNIT, "802.11a/g MCS choice: adaptive, or a fixed level mcs0..mcs6"),
    "mission": (NO_UNIT, f"the UAVs' mission: one of {', '.join(v.MISSIONS)}"),
    "tx_dbm": ("dBm", "transmit power of every radio"),
    "noise_dbm": ("dBm", "noise floor (the scenario's 95 is -95.0)"),
}
_COUNTS: dict[str, tuple[str, str]] = {
    "packets": ("packets",
                "packets of the row (flows: each transmission once, at the capture point when it crossed it; "
                "episodes: sent or received by the node)"),
    "bytes": ("bytes", "sum of the flow's frame lengths (link-layer, as tshark frame.len)"),
    "duration_s": ("s", "last packet time - first packet time"),
}
_SEQUENCES: dict[str, tuple[str, str]] = {
    "seq_time_s": ("s", "each packet's time since the flow's first packet"),
    "seq_size": ("bytes", "each packet's frame length"),
    "seq_flags": (NO_UNIT, "each packet's TCP flags (0 for other protocols, -1 where an imported file had none)"),
    "seq_dir": (NO_UNIT, "each packet's direction: +1 forward (initiator -> responder), -1 backward"),
    "seq_effect": (NO_UNIT, f"each packet's ground-truth effect: one of {', '.join(v.EFFECTS)}"),
}
_TRUTH: dict[str, tuple[str, str]] = {
    "attack_packets": ("packets", f"packets with an attack effect ({', '.join(v.ATTACK_EFFECTS)})"),
    "attack_fraction": ("ratio", "attack_packets / packets, exactly"),
    "provoked_packets": ("packets", "of attack_packets, those whose effect is provoked (answers to attack packets)"),
    "label": (NO_UNIT, "the class: Benign, one family's class or a composition's (vocabulary.CLASSES)"),
    "label_source": (NO_UNIT,
                     "the labelling rules that fired (uavcas.labels.label.SOURCES), joined by +; none: Benign"),
}
for _f in v.FAMILIES:
    _TRUTH[f"attack_packets_{_f}"] = ("packets", f"attack packets whose effect comes from a {_f} attack "
                                                 f"(provoked: the provoking family)")
    _TRUTH[f"label_{_f}"] = (NO_UNIT, f"the row carries family {_f} (class {v.FAMILY_CLASS[_f]}); multi-hot")

# context columns (uavcas.flows.context; docs/formats.md "Context columns" says what a node must observe)
_CTX_FLOW: dict[str, tuple[str, str]] = {
    "ctx_path_len_mean": ("switches", "mean number of switches that saw each of the flow's packets"),
    "ctx_delay_ms": ("ms", "mean first-to-last observation time of packets seen at >= 2 switches (-1: none)"),
    "ctx_lost_frac": ("ratio", "share of the flow's packets its destination's switch never saw"),
    "ctx_offhome_frac": ("ratio", "share of packets that entered the network away from their source's home switch"),
    "ctx_ttl_off_frac": ("ratio", "share of packets whose TTL is not their source's usual TTL"),
    "ctx_ttl_levels": ("TTL values", "distinct TTLs per direction less one, the larger direction"),
    "ctx_neardup_frac": ("ratio",
                         "share of packets repeating an earlier one's IP id, length and flags with another seq or TTL"),
    "ctx_retx_frac": ("ratio", "share of packets repeating an earlier data/SYN/FIN packet (retransmissions)"),
    "ctx_seq_regress_frac": ("ratio",
                             "share of data packets whose TCP seq lies below the highest sent before (stale copies)"),
    "ctx_rtt_ms": ("ms", "first SYN entering the network to the first SYN-ACK's last observation (-1: no handshake)"),
    "ctx_route_lonely_frac": ("ratio", "share of the flow's packets whose directed host pair's last route change "
                                       "(switch sequence, 1 s bins) came while < 20 % of the network's pairs, "
                                       "or only pairs joining the same two home switches, changed (that bin or "
                                       "the one before)"),
    "ctx_path_len_shift_max": ("switches", "over the windows the flow's packets crossed, the largest mean of (switches "
                                           "that saw a packet less the median of its directed pair's earlier windows)"),
    "ctx_delay_shift_max_ms": ("ms", "likewise for first-to-last observation time, against the pair's earlier median "
                                     "delay"),
    # the window-host view's own route columns, over the episode's packets
    "ctx_pkt_route_lonely_frac": ("ratio",
                                  "share of the episode's packets on a lonely route (as ctx_route_lonely_frac)"),
    "ctx_pkt_route_lonely_max": ("ratio", "the largest such share over the node's peers (the other end's address)"),
    "ctx_pkt_path_len_shift_peer_max": ("switches", "the largest mean path shift over the node's peers' packets"),
    "ctx_pkt_delay_shift_peer_max_ms": ("ms", "the largest mean one-way delay shift over the node's peers' packets"),
    "ctx_pkt_off_own_route_frac": ("ratio", "share of the episode's packets that a switch sent another way than "
                                            "the nearest packet (within 0.5 s) of the other kind (its own or passing "
                                            "traffic) to the same destination, else toward any base station if the "
                                            "destination is at one (of those where one was seen)"),
    "ctx_pkt_off_own_route_max": ("ratio", "the largest such share over the node's peers (the other end's address)"),
    "ctx_pkt_passing_off_route_frac": ("ratio", "likewise, counted only at the switches where the packet was passing "
                                                "traffic (not its source's home)"),
    "ctx_pkt_passing_off_route_max": ("ratio", "the largest such share over the node's peers"),
    "ctx_pkt_lonely_off_route_frac": ("ratio", "share of the episode's packets both sent off the other kind's way "
                                               "(as ctx_pkt_off_own_route_frac) and on a lonely route (as "
                                               "ctx_pkt_route_lonely_frac)"),
    "ctx_pkt_lonely_off_route_max": ("ratio", "the largest such share over the node's peers"),
    "ctx_pkt_path_len_shift": ("switches", "mean over the episode's packets of switches that saw it less its directed "
                                           "pair's earlier median"),
    "ctx_pkt_delay_shift_ms": ("ms", "mean over the episode's packets of first-to-last observation time less its "
                                     "directed pair's earlier median"),
}
_CTX_METRIC: dict[str, tuple[str, str]] = {
    "flow_share": ("ratio", "share of the window's flows that have it as an endpoint"),
    "unanswered_frac": ("ratio", "share of its request flows with no packet back"),
    "rtt_ms": ("ms", "median ctx_rtt_ms of its flows (-1: none)"),
    "delay_ms": ("ms", "median delay of its transmissions seen at >= 2 switches (-1: none)"),
    "out_share": ("ratio", "share of its transmissions that it sent"),
    "lost_out_frac": ("ratio", "share of transmissions from it that never reached their destination's switch"),
    "lost_in_frac": ("ratio", "share of transmissions to it that never reached its switch"),
    "lost_frac": ("ratio", "share of its transmissions that never reached their destination's switch"),
    "offhome_frac": ("ratio", "share of its transmissions that entered away from their source's home switch"),
    "ttl_off_frac": ("ratio", "share of its transmissions with an unusual TTL"),
    "path_len_mean": ("switches", "mean number of switches that saw each of its transmissions"),
    "flows_log_ratio": ("ln ratio", "ln((1 + flows) / (1 + median flows of its earlier windows))"),
    "unanswered_shift": ("ratio", "unanswered_frac less the median of its earlier windows"),
    "rtt_shift_ms": ("ms", "rtt_ms less the median of its earlier windows"),
    "delay_shift_ms": ("ms", "delay_ms less the median of its earlier windows"),
    "out_share_shift": ("ratio", "out_share less the median of its earlier windows"),
    "lost_out_shift": ("ratio", "lost_out_frac less the median of its earlier windows"),
    "path_len_shift": ("switches", "path_len_mean less the median of its earlier windows"),
}
_CTX_SUBJECT = {"src": "the flow's initiator in the window", "dst": "the flow's responder in the window",
                "pair": "the flow's host pair in the window", "net": "the whole network in the window"}
_CTX_OWN_SHIFT = {"ctx_rtt_shift_ms": "ctx_rtt_ms", "ctx_delay_shift_ms": "ctx_delay_ms",
                  "ctx_path_len_shift": "ctx_path_len_mean"}


def context_entry(name: str) -> tuple[str, str] | None:
    if name in _CTX_FLOW:
        return _CTX_FLOW[name]
    if name in _CTX_OWN_SHIFT:
        base = _CTX_OWN_SHIFT[name]
        return _CTX_FLOW[base][0], f"the flow's {base} less the median of its host pair's earlier windows"
    for subject, who in _CTX_SUBJECT.items():
        prefix = f"ctx_{subject}_"
        if name.startswith(prefix) and name[len(prefix):] in _CTX_METRIC:
            unit, what = _CTX_METRIC[name[len(prefix):]]
            return unit, f"{who}: {what}"
    return None


def feature_entry(name: str, standard: str) -> tuple[str, str] | None:
    """(unit, meaning) of a feature of the standard (None: none of its columns)."""
    std = feature_standard(standard)
    if name not in std.units:
        return None
    return std.units[name], f"{std.meanings[name]} [{std.name}]"


def describe(name: str, standard: str, view: "ViewSpec") -> tuple[str, str]:
    """(unit, meaning) of column `name` of a dataset of feature standard `standard` whose rows
    are of `view` (`uavcas.views`: the entries of the view's own columns are its)."""
    for table in (_IDS, _AXES, _COUNTS, _SEQUENCES, _TRUTH):
        if name in table:
            return table[name]
    found = view.describe(name, standard)
    if found is None:
        raise DictionaryError(f"column {name!r} has no entry in the data dictionary (uavcas.dataset.dictionary)")
    return found


def field_metadata(name: str, standard: str, view: "ViewSpec") -> dict[bytes, bytes]:
    """The Parquet field metadata of a column: b"unit" and b"meaning"."""
    unit, meaning = describe(name, standard, view)
    return {b"unit": unit.encode(), b"meaning": meaning.encode()}


def columns(arrow_schema, standard: str, view: "ViewSpec") -> list[Column]:
    """Every column of `arrow_schema` (a pyarrow Schema: a dataset's file or a shard's of `view`) described."""
    return [Column(f.name, str(f.type), *describe(f.name, standard, view)) for f in arrow_schema]


def card_columns(arrow_schema, standard: str, view: "ViewSpec") -> dict[str, dict]:
    """The card's `columns`: name -> {dtype, unit, meaning}, in file order."""
    return {c.name: {"dtype": c.dtype, "unit": c.unit, "meaning": c.meaning}
            for c in columns(arrow_schema, standard, view)}


def markdown_table(cols: list[Column]) -> list[str]:
    """The lines of a Markdown table of columns: name, dtype, unit, meaning."""
    rows = ["| column | dtype | unit | meaning |", "|---|---|---|---|"]
    return rows + [f"| `{c.name}` | {c.dtype} | {c.unit} | {c.meaning.replace('|', '/')} |" for c in cols]
