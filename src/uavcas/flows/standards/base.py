"""What a feature standard is: one record naming a standard's columns, their units and meanings,
where the definitions come from, and the function that computes them.

A standard (`FeatureStandard`, one per module of this package, registered by name) owns
- its columns in stored order (a dataset's feature columns are exactly these, `flows.features`),
- the unit and the one-line meaning of each (the dataset card, the data dictionary, the Parquet
  field metadata and docs/formats.md read them: `uavcas.dataset.dictionary`),
- its source (the tool, file and version whose definitions it follows),
- `compute`: the columns of every flow of a capture, from its packets in flow order,
- the subset of its columns summarised per window-host episode (`uavcas.labels.episodes`).

Layers outside this package ask the registry (`uavcas.flows.standards.standard(name)`) and never
test a standard's name themselves.
"""

from __future__ import annotations

import re
from collections.abc import Callable, Mapping
from dataclasses import dataclass

import numpy as np

from uavcas.schema import EPISODE_PACKET_UNITS, EPISODE_STATS

from ..assemble import Flows
from ..packets import PacketTable

_NAME = re.compile(r"^[a-z][a-z0-9_-]*$")  # a CLI word and a card value


@dataclass(frozen=True)
class FlowPackets:
    """A capture's flows with their packets: what a standard computes its columns from."""

    packets: PacketTable
    flows: Flows
    src_ip: np.ndarray  # per flow: the forward endpoint's address text (`flows.features` identity)
    dst_ip: np.ndarray

    def ordered(self, column: str) -> np.ndarray:
        """A packet column in flow order: flow 0's packets first, each flow's in time order."""
        return self.packets[column][self.flows.order]


Compute = Callable[[FlowPackets], Mapping[str, np.ndarray]]


@dataclass(frozen=True, eq=False)
class FeatureStandard:
    """One feature standard. `units` and `meanings` cover exactly `columns`; `episode_summary`
    maps some of the columns to the stem of their window-host columns (unit in the stem; each
    gives <stem>_mean and <stem>_max)."""

    name: str
    columns: tuple[str, ...]
    units: Mapping[str, str]
    meanings: Mapping[str, str]
    source: str  # whose definitions: tool / repository, file, version
    summary: str  # a few words for the CLI help: what the values are and their time unit
    compute: Compute
    episode_summary: Mapping[str, str]

    def __post_init__(self) -> None:
        where = f"feature standard {self.name!r}"
        if not _NAME.match(self.name):
            raise ValueError(f"{where}: a name is lower-case letters, digits, '-' or '_'")
        if not self.columns or len(set(self.columns)) != len(self.columns):
            raise ValueError(f"{where}: columns must be non-empty and unique")
        for what, table in (("units", self.units), ("meanings", self.meanings)):
            if set(table) != set(self.columns):
                raise ValueError(f"{where}: {what} do not cover exactly its columns "
                                 f"(differ on {sorted(set(table) ^ set(self.columns))})")
        if not set(self.episode_summary) <= set(self.columns):
            raise ValueError(f"{where}: episode_summary names columns it lacks: "
                             f"{sorted(set(self.episode_summary) - set(self.columns))}")
        if len(set(self.episode_summary.values())) != len(self.episode_summary):
            raise ValueError(f"{where}: episode_summary stems must be unique")

    @property
    def module(self) -> str:
        """The module that defines it (named on the dataset card beside the source)."""
        return self.compute.__module__

    def features(self, fp: FlowPackets) -> dict[str, np.ndarray]:
        """Its columns for every flow of `fp`, float64, in stored order."""
        got = self.compute(fp)
        if set(got) != set(self.columns):
            raise ValueError(f"feature standard {self.name!r} computed {sorted(set(got) ^ set(self.columns))} "
                             "beside or instead of its columns")
        return {c: np.asarray(got[c], dtype=np.float64) for c in self.columns}

    @property
    def episode_columns(self) -> tuple[str, ...]:
        """The window-host view's feature columns when its flows follow this standard."""
        return tuple(EPISODE_PACKET_UNITS) + tuple(
            f"{stem}_{s}" for stem in self.episode_summary.values() for s in EPISODE_STATS)

    @property
    def episode_units(self) -> dict[str, str]:
        """Unit of every episode feature column: the packet counts', then the summarised features'."""
        units = dict(EPISODE_PACKET_UNITS)
        for feat, stem in self.episode_summary.items():
            units.update({f"{stem}_{s}": self.units[feat] for s in EPISODE_STATS})
        return units
