"""What a dataset view is: one record naming the rows a run is extracted to, their columns and
how they are made.

A view (`ViewSpec`, one per module of this package, registered by name) owns
- its name (the `--view` word, the rows' `view` column, the card's `views`) and what one row is
  called (`RowNoun`: "flow" / "flows", "host-window row" / "host-window rows"),
- the words the dataset's files use for its rows: the card's `unit`, the Croissant record set,
  the README's and Croissant's sentence saying what a row is, the report's figures and title,
- its key (the columns that identify a row within a run) and its columns: the Arrow fields per
  feature standard (`fields`), the feature and context columns the IDS reads, the metadata
  columns it must never read, and the data-dictionary entries of its own columns (`describe`;
  the columns every view shares are `uavcas.dataset.dictionary`'s),
- its extraction and labeller (`rows`): one run's packets, flows (`flow_key`), context and
  truth -> its labelled rows.

Layers outside this package ask the registry (`uavcas.views.view(name)`, or the view a dataset
records) and never test a view's name themselves.
"""

from __future__ import annotations

import re
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import TYPE_CHECKING

import pandas as pd
import pyarrow as pa

from uavcas.flows.assemble import VIEWS as FLOW_KEYS
from uavcas.flows.standards import feature_columns
from uavcas.schema import AXIS_COLUMNS, LABEL_COLUMNS, TRUTH_COLUMNS

if TYPE_CHECKING:
    from uavcas.flows.assemble import Flows
    from uavcas.flows.context import PacketRoutes
    from uavcas.flows.packets import PacketTable
    from uavcas.labels.attacklog import AttackLog
    from uavcas.labels.effects import PacketTruth
    from uavcas.twin.model import Plan

_NAME = re.compile(r"^[a-z0-9][a-z0-9-]*$")  # a CLI word and a column value

# Arrow types of the columns every view has: the run's identity and time span, its axes
IDENTITY_TYPES: dict[str, pa.DataType] = {
    "run_id": pa.string(), "config": pa.string(), "seed": pa.int64(), "view": pa.string(),
    "first_ts": pa.float64(), "last_ts": pa.float64(), "first_ts_ns": pa.int64(),
}  # fmt: skip
AXIS_TYPES: dict[str, pa.DataType] = {
    "attacks": pa.string(), "n_uav": pa.int64(), "n_bs": pa.int64(), "payload": pa.string(),
    "pathloss": pa.string(), "modulation": pa.string(), "mission": pa.string(), "tx_dbm": pa.int64(),
    "noise_dbm": pa.float64(),
}  # fmt: skip


def axis_fields() -> list[pa.Field]:
    """The scenario's axes (`Scenario.axes()`), as every view stores them."""
    return [pa.field(c, AXIS_TYPES[c]) for c in AXIS_COLUMNS]


def label_fields() -> list[pa.Field]:
    """Truth and label columns, the same for every view: counts int64, attack_fraction float64,
    label_<family> bool, label and label_source string."""
    fields = [pa.field(c, pa.float64() if c == "attack_fraction" else pa.int64()) for c in TRUTH_COLUMNS]
    fields += [pa.field(c, pa.bool_()) for c in LABEL_COLUMNS]
    return fields + [pa.field("label", pa.string()), pa.field("label_source", pa.string())]


@dataclass(frozen=True)
class RowNoun:
    """What one row of a view is called, in the singular and the plural."""

    singular: str
    plural: str


@dataclass(frozen=True)
class ViewInput:
    """What a view's rows are made from: one run's packets (every capture point), their flows by
    the view's `flow_key` and those flows' frame (row i = flow i: identity, counts, sequences, the
    standard's features), the flows' context columns and the packets' routes (None: not computed),
    the attack log, each packet's truth, the plan and its t = 0, and the extraction's options."""

    packets: "PacketTable"
    flows: "Flows"
    frame: pd.DataFrame
    context: pd.DataFrame | None
    routes: "PacketRoutes | None"
    log: "AttackLog"
    truth: "PacketTruth"
    plan: "Plan"
    t0_unix: float
    standard: str
    labels: str
    min_attack_fraction: float


@dataclass(frozen=True)
class ViewRows:
    """A view's labelled rows of one run (the run's identity and axis columns are added by
    `uavcas.extract`), the rows left out by a labelling rule, and that rule in words (the card)."""

    frame: pd.DataFrame
    impure_dropped: int
    label_rule: str


Fields = Callable[[str, bool], list[pa.Field]]  # (standard, context) -> Arrow fields in stored order
Describe = Callable[[str, str], "tuple[str, str] | None"]  # (column, standard) -> (unit, meaning)


@dataclass(frozen=True, eq=False)
class ViewSpec:
    """One dataset view (module docstring)."""

    name: str
    row: RowNoun
    unit: str  # the card's `unit`: one word for what a row is (views of one unit share a dataset)
    meaning: str  # "one row = <meaning>" (Croissant's record set)
    card_rows: str  # the README's "Rows: N (<card_rows>)"
    record_set: str  # Croissant record set name
    help: str  # the `--view` help: what a row is
    key_columns: tuple[str, ...]  # identify a row within a run
    flow_key: str  # the flows the rows are made from (`uavcas.flows.assemble.VIEWS`)
    flow_labels: bool  # takes the flow labelling options (--labels paper, --min-attack-fraction)
    fields: Fields
    feature_columns: Callable[[str], tuple[str, ...]]  # standard -> the features the IDS reads
    context_columns: tuple[str, ...]  # the ctx_* columns (all or none are stored)
    metadata_columns: tuple[str, ...]  # identity, axes, counts, truth, labels: never a feature
    describe: Describe  # the data dictionary's entries of the view's own columns (None: not its)
    feature_card: Callable[[str], Mapping]  # standard -> the card's `features` record
    shown_features: tuple[str, ...]  # the report's feature distributions per class
    report_title: str
    rows: Callable[[ViewInput], ViewRows]

    def __post_init__(self) -> None:
        where = f"view {self.name!r}"
        if not _NAME.match(self.name):
            raise ValueError(f"{where}: a name is lower-case letters, digits and '-'")
        if self.flow_key not in FLOW_KEYS:
            raise ValueError(f"{where}: flow_key {self.flow_key!r} is not one of {', '.join(FLOW_KEYS)}")
        if not self.key_columns or not set(self.key_columns) <= set(self.metadata_columns):
            raise ValueError(f"{where}: key columns must be among its metadata columns")

    @property
    def is_flow(self) -> bool:
        """Its rows are flows (of its flow key, with packet sequences): what the flow CSV exports hold."""
        return self.unit == "flow"

    def check_options(self, labels: str, min_attack_fraction: float) -> None:
        """Refuse, before any work, the flow labelling options on a view that labels otherwise."""
        if not self.flow_labels and (labels != "ours" or min_attack_fraction > 0):  # both are rules about flows
            raise ValueError(f"the {self.name} view labels {self.row.plural} from packet effects: it takes "
                             "neither --labels paper nor --min-attack-fraction")

    def feature_set(self, standard: str) -> str:
        """The name of the IDS feature set of this view's rows of `standard` (`uavcas.ids.features`):
        the standard's own name where the rows carry its flow features, else <view>-<standard>."""
        return standard if self.feature_columns(standard) == feature_columns(standard) else f"{self.name}-{standard}"
