"""What the flow views share: one row per flow of a flow key (`uavcas.flows.assemble`), its
identity, counts, packet sequences, the standard's features and the context columns, labelled by
`uavcas.labels.label` (both label modes, `min_attack_fraction`). `flow_view` builds the spec of
one key; the modules `five_tuple`, `host_pair` and `window_host_pair` register one each.
"""

from __future__ import annotations

import pyarrow as pa

from uavcas.dataset.dictionary import context_entry, feature_entry
from uavcas.flows.standards import feature_columns
from uavcas.flows.standards import standard as feature_standard
from uavcas.labels.label import label_flows, rule_text
from uavcas.schema import CONTEXT_FEATURES, COUNT_COLUMNS, ID_COLUMNS, METADATA_COLUMNS, SEQUENCE_COLUMNS

from .base import IDENTITY_TYPES, RowNoun, ViewInput, ViewRows, ViewSpec, axis_fields, label_fields

ID_TYPES: dict[str, pa.DataType] = {
    **IDENTITY_TYPES, "flow_id": pa.int64(), "src_ip": pa.string(), "src_port": pa.int32(), "dst_ip": pa.string(),
    "dst_port": pa.int32(), "protocol": pa.int16(), "capture_point": pa.string(),
}  # fmt: skip
COUNT_TYPES: dict[str, pa.DataType] = {"packets": pa.int64(), "bytes": pa.int64(), "duration_s": pa.float64()}
SEQUENCE_TYPES: dict[str, pa.DataType] = {
    "seq_time_s": pa.list_(pa.float64()), "seq_size": pa.list_(pa.int32()), "seq_flags": pa.list_(pa.int16()),
    "seq_dir": pa.list_(pa.int8()), "seq_effect": pa.list_(pa.string()),
}  # fmt: skip
# Features shown per class in the report: time structure, volume and size, the ones the paper's figures use.
SHOWN_FEATURES = ("Flow IAT Mean", "Flow Packets/s", "Flow Duration", "Packet Length Mean", "Total Fwd Packets",
                  "SYN Flag Count")


def flow_fields(standard: str, context: bool) -> list[pa.Field]:
    """A flow shard's columns: identity, axes, counts, sequences, the standard's features, the
    context columns when `context`, truth and labels."""
    fields = [pa.field(c, ID_TYPES[c]) for c in ID_COLUMNS] + axis_fields()
    fields += [pa.field(c, COUNT_TYPES[c]) for c in COUNT_COLUMNS]
    fields += [pa.field(c, SEQUENCE_TYPES[c]) for c in SEQUENCE_COLUMNS]
    fields += [pa.field(c, pa.float64()) for c in feature_columns(standard)]
    fields += [pa.field(c, pa.float64()) for c in (CONTEXT_FEATURES if context else ())]
    return fields + label_fields()


def describe_flow_column(name: str, standard: str) -> tuple[str, str] | None:
    """A flow's feature (the standard's unit and meaning) or context column."""
    return feature_entry(name, standard) or context_entry(name)


def flow_feature_card(standard: str) -> dict:
    """The card's record of the standard: its name, source and the unit of every column."""
    std = feature_standard(standard)
    return {"standard": std.name, "source": f"{std.source} ({std.module})", "units": dict(std.units)}


def label_flow_rows(inp: ViewInput) -> ViewRows:
    """The flows labelled (`uavcas.labels.label.label_flows`), with their context columns."""
    lab = label_flows(inp.flows, inp.frame, inp.log, inp.truth, mode=inp.labels,  # type: ignore[arg-type]
                      min_attack_fraction=inp.min_attack_fraction)
    df = lab.frame
    if inp.context is not None:  # label_flows keeps flow_id: rows may have been left out, never reordered
        df[list(CONTEXT_FEATURES)] = inp.context.to_numpy()[df["flow_id"].to_numpy()]
    return ViewRows(df, lab.impure_dropped, rule_text(inp.labels, inp.min_attack_fraction))


def flow_view(name: str, help: str) -> ViewSpec:
    """The spec of the flow view of flow key `name` (`uavcas.flows.assemble.VIEWS`)."""
    return ViewSpec(
        name=name, row=RowNoun("flow", "flows"), unit="flow", meaning="one flow", card_rows="one per flow",
        record_set="flows", help=help, key_columns=("flow_id",), flow_key=name, flow_labels=True,
        fields=flow_fields, feature_columns=feature_columns, context_columns=CONTEXT_FEATURES,
        metadata_columns=METADATA_COLUMNS, describe=describe_flow_column, feature_card=flow_feature_card,
        shown_features=SHOWN_FEATURES, report_title="Flow features per class", rows=label_flow_rows,
    )
