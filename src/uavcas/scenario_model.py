"""The scenario's typed form, as pure data: its axes and its attacks' typed parameters.

A module of its own at the top of the package, not in `uavcas.scenario`, whose `__init__` loads
the codec and with it every family: the families import this module.

`Scenario` and `SpecBase` (the base every family's spec extends) sit below the attack families
and the plan contract (`uavcas.twin.model` holds a `Scenario` and one spec per attack), so they
import no family. Turning text into them is the families' work, through the registry: the
string by the codec (`uavcas.scenario.codec.parse`), the JSON of a plan by the plan reader
(`uavcas.twin.load`), which hands the family specs in through `SpecReader`.
"""

from __future__ import annotations

import re
from typing import Any, Protocol

from pydantic import BaseModel, ConfigDict, Field, SerializeAsAny, ValidationInfo, field_validator

from uavcas.channel.pathloss import PathlossName
from uavcas.traffic.payloads import DEFAULT_PAYLOAD, PayloadName
from uavcas.vocabulary import BENIGN_TOKEN, FAMILIES, Mission

# The key under which the plan reader puts its `SpecReader` into pydantic's validation context.
SPEC_READER = "spec_reader"


class ScenarioError(ValueError):
    """A malformed scenario string; the message is one line and names the bad field."""


_INT = re.compile(r"^(0|[1-9][0-9]*)$")
MCS_LEVEL = re.compile(r"^mcs([0-6])$")  # a fixed modulation level


def int_field(name: str, raw: str, lo: int, hi: int) -> int:
    if not _INT.match(raw):
        raise ScenarioError(f"field '{name}': expected a non-negative integer, got {raw!r}")
    v = int(raw)
    if not lo <= v <= hi:
        raise ScenarioError(f"field '{name}': {v} is outside [{lo}, {hi}]")
    return v


def choice(name: str, raw: str, choices: tuple[str, ...]) -> str:
    if raw not in choices:
        raise ScenarioError(f"field '{name}': {raw!r} is not one of {', '.join(choices)}")
    return raw


class SpecBase(BaseModel):
    """Typed parameters of one attack token of a scenario string. Each family's subclass declares
    `family` (a Literal of its names) as its first field."""

    model_config = ConfigDict(frozen=True, extra="forbid")

    def token(self) -> str:
        return self.family  # type: ignore[attr-defined]


class SpecReader(Protocol):
    """What reading specs from JSON asks of the layer that knows the families (`uavcas.twin.load`
    implements it with the registry): this layer cannot know the families' spec classes."""

    def spec(self, family: str, data: Any) -> SpecBase:
        """The spec of `family` from its JSON form (the family validates its own parameters)."""

    def spec_from_params(self, family: str, params: dict[str, Any]) -> SpecBase:
        """The spec of a plan attack written before attacks carried one (its `params`)."""

    def scenario(self, config: str) -> Scenario | None:
        """The scenario of a config string; None when it is none (hand-made plans)."""


def spec_reader(info: ValidationInfo, what: str) -> SpecReader:
    """The reader the validation context carries; a one-line error naming `what` without one."""
    reader = (info.context or {}).get(SPEC_READER)
    if reader is None:
        raise ValueError(f"{what}: attack specs are read by their families; read plans with uavcas.twin.load "
                         "(or build specs with uavcas.attacks.family(name))")
    return reader


def read_spec(raw: Any, info: ValidationInfo, what: str) -> Any:
    """A spec given as data (a dict from JSON) read by its family; a spec object as it is."""
    if isinstance(raw, dict) and raw.get("family") in FAMILIES:
        return spec_reader(info, what).spec(raw["family"], raw)
    return raw


class Scenario(BaseModel):
    model_config = ConfigDict(frozen=True, extra="forbid")

    # empty = benign; canonical family order; each the spec class of its family
    attacks: tuple[SerializeAsAny[SpecBase], ...] = ()
    n_uav: int = Field(ge=1, le=250)
    n_bs: int = Field(ge=1, le=16)
    payload: PayloadName = DEFAULT_PAYLOAD  # a row of the payload table (uavcas.traffic.payloads)
    pathloss: PathlossName = "logdist"  # a name of the path-loss registry
    modulation: str = "adaptive"  # "adaptive" or a fixed level "mcs0".."mcs6"
    mission: Mission = "random"
    tx_dbm: int = 30
    noise: int = 95  # positive magnitude: the noise floor is -noise dBm

    @field_validator("attacks", mode="before")
    @classmethod
    def _read_specs(cls, v: Any, info: ValidationInfo) -> Any:
        if isinstance(v, (list, tuple)):
            return tuple(read_spec(a, info, "scenario") for a in v)
        return v

    @field_validator("attacks")
    @classmethod
    def _canonical_order(cls, v: tuple) -> tuple:
        return tuple(sorted(v, key=lambda a: FAMILIES.index(a.family)))

    @property
    def noise_dbm(self) -> float:
        return -float(self.noise)

    @property
    def families(self) -> tuple[str, ...]:
        return tuple(a.family for a in self.attacks)

    @property
    def fixed_mcs(self) -> int | None:
        m = MCS_LEVEL.match(self.modulation)
        return int(m.group(1)) if m else None

    def attack(self, name: str):
        for a in self.attacks:
            if a.family == name:
                return a
        return None

    @property
    def attacks_token(self) -> str:
        return "+".join(a.token() for a in self.attacks) or BENIGN_TOKEN

    def to_string(self) -> str:
        return "-".join(
            str(v)
            for v in (
                self.attacks_token,
                self.n_uav,
                self.n_bs,
                self.payload,
                self.pathloss,
                self.modulation,
                self.mission,
                self.tx_dbm,
                self.noise,
            )
        )

    def __str__(self) -> str:
        return self.to_string()

    def axes(self) -> dict[str, object]:
        """Axis values as flat columns (for datasets and per-axis analysis): vocabulary.AXIS_COLUMNS."""
        return {
            "attacks": self.attacks_token,
            "n_uav": self.n_uav,
            "n_bs": self.n_bs,
            "payload": self.payload,
            "pathloss": self.pathloss,
            "modulation": self.modulation,
            "mission": self.mission,
            "tx_dbm": self.tx_dbm,
            "noise_dbm": self.noise_dbm,
        }
