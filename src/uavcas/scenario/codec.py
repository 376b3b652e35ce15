"""The paper's 9-field scenario string and its typed form.

`<attacks>-<n_uav>-<n_bs>-<payload>-<pathloss>-<modulation>-<mission>-<tx_dbm>-<noise>`, e.g.
`blackhole+dos=1000-20-2-image-logdist-adaptive-random-30-95` (noise 95 means -95 dBm).
Parsing then formatting gives the input back byte for byte; anything else is refused with a
one-line `ScenarioError` naming the field at fault.
"""

from __future__ import annotations

import re
from typing import Annotated, Literal, Union

from pydantic import BaseModel, ConfigDict, Field

FIELD_NAMES = (
    "attacks",
    "n_uav",
    "n_bs",
    "payload",
    "pathloss",
    "modulation",
    "mission",
    "tx_dbm",
    "noise",
)
PAYLOADS = ("image", "telemetry", "mixed")
PATHLOSS_MODELS = ("logdist", "3gpp", "uma", "rma", "umi", "tworay", "freespace")
MISSIONS = ("spiral", "grid", "hover_transit", "random")
SEQ_MODES = ("inc", "rand", "zero")
# Canonical token order (alphabetical by family) = the order of the paper's composition names.
FAMILY_ORDER = ("blackhole", "ddos", "dos", "replay", "wormhole")

_INT = re.compile(r"^(0|[1-9][0-9]*)$")
_MCS = re.compile(r"^mcs([0-6])$")


class ScenarioError(ValueError):
    """A malformed scenario string; the message is one line and names the bad field."""


class _Frozen(BaseModel):
    model_config = ConfigDict(frozen=True, extra="forbid")


class Flood(_Frozen):
    family: Literal["dos", "ddos"]
    interval_us: int = Field(gt=0)  # hping3 inter-packet interval: 1000 us ~ 1,000 SYN/s nominal

    @property
    def nominal_pps(self) -> float:
        return 1e6 / self.interval_us

    def token(self) -> str:
        return f"{self.family}={self.interval_us}"


class Blackhole(_Frozen):
    family: Literal["blackhole"] = "blackhole"

    def token(self) -> str:
        return "blackhole"


class Wormhole(_Frozen):
    family: Literal["wormhole"] = "wormhole"

    def token(self) -> str:
        return "wormhole"


class Replay(_Frozen):
    family: Literal["replay"] = "replay"
    buffer_pkts: int = Field(gt=0)
    delay_ms: int = Field(ge=0)
    rate_pps: int = Field(gt=0)
    ttl_dec: int = Field(ge=0, le=254)
    seq_mode: Literal["inc", "rand", "zero"]

    def token(self) -> str:
        return (
            f"replay={self.buffer_pkts},{self.delay_ms},{self.rate_pps},"
            f"{self.ttl_dec},{self.seq_mode}"
        )


AttackSpec = Annotated[Union[Flood, Blackhole, Wormhole, Replay], Field(discriminator="family")]


class Scenario(_Frozen):
    attacks: tuple[AttackSpec, ...] = ()  # empty = benign
    n_uav: int = Field(ge=1, le=250)
    n_bs: int = Field(ge=1, le=16)
    payload: Literal["image", "telemetry", "mixed"] = "image"
    pathloss: Literal["logdist", "3gpp", "uma", "rma", "umi", "tworay", "freespace"] = "logdist"
    modulation: str = "adaptive"  # "adaptive" or a fixed level "mcs0".."mcs6"
    mission: Literal["spiral", "grid", "hover_transit", "random"] = "random"
    tx_dbm: int = 30
    noise: int = 95  # positive magnitude: the noise floor is -noise dBm

    @property
    def noise_dbm(self) -> float:
        return -float(self.noise)

    @property
    def families(self) -> tuple[str, ...]:
        return tuple(a.family for a in self.attacks)

    @property
    def fixed_mcs(self) -> int | None:
        m = _MCS.match(self.modulation)
        return int(m.group(1)) if m else None

    def attack(self, family: str):
        for a in self.attacks:
            if a.family == family:
                return a
        return None

    def to_string(self) -> str:
        attacks = "+".join(a.token() for a in self.attacks) or "benign"
        return "-".join(
            str(v)
            for v in (
                attacks,
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

    @classmethod
    def parse(cls, text: str) -> "Scenario":
        return parse(text)

    def axes(self) -> dict[str, object]:
        """Axis values as flat columns (for datasets and per-axis analysis)."""
        return {
            "attacks": "+".join(a.token() for a in self.attacks) or "benign",
            "n_uav": self.n_uav,
            "n_bs": self.n_bs,
            "payload": self.payload,
            "pathloss": self.pathloss,
            "modulation": self.modulation,
            "mission": self.mission,
            "tx_dbm": self.tx_dbm,
            "noise_dbm": self.noise_dbm,
        }


def _int_field(name: str, raw: str, lo: int, hi: int) -> int:
    if not _INT.match(raw):
        raise ScenarioError(f"field '{name}': expected a non-negative integer, got {raw!r}")
    v = int(raw)
    if not lo <= v <= hi:
        raise ScenarioError(f"field '{name}': {v} is outside [{lo}, {hi}]")
    return v


def _choice(name: str, raw: str, choices: tuple[str, ...]) -> str:
    if raw not in choices:
        raise ScenarioError(f"field '{name}': {raw!r} is not one of {', '.join(choices)}")
    return raw


def _parse_attack(tok: str):
    name, eq, arg = tok.partition("=")
    if name in ("dos", "ddos"):
        if not eq:
            raise ScenarioError(f"field 'attacks': {name} needs an interval in us, e.g. {name}=1000")
        return Flood(family=name, interval_us=_int_field(f"attacks.{name}", arg, 1, 10_000_000))
    if name in ("blackhole", "wormhole"):
        if eq:
            raise ScenarioError(f"field 'attacks': {name} takes no value, got {tok!r}")
        return Blackhole() if name == "blackhole" else Wormhole()
    if name == "replay":
        parts = arg.split(",") if eq else []
        if len(parts) != 5:
            raise ScenarioError(
                "field 'attacks': replay needs 5 values "
                f"<buffer>,<delay_ms>,<pps>,<ttl_dec>,<inc|rand|zero>, got {tok!r}"
            )
        buf, delay, pps, ttl, mode = parts
        return Replay(
            buffer_pkts=_int_field("attacks.replay.buffer", buf, 1, 1_000_000),
            delay_ms=_int_field("attacks.replay.delay_ms", delay, 0, 3_600_000),
            rate_pps=_int_field("attacks.replay.pps", pps, 1, 1_000_000),
            ttl_dec=_int_field("attacks.replay.ttl_dec", ttl, 0, 254),
            seq_mode=_choice("attacks.replay.seq_mode", mode, SEQ_MODES),
        )
    raise ScenarioError(
        f"field 'attacks': unknown attack token {tok!r} "
        "(benign, dos=<us>, ddos=<us>, blackhole, wormhole, replay=<buf>,<ms>,<pps>,<ttl>,<mode>)"
    )


def parse(text: str) -> Scenario:
    if not isinstance(text, str) or not text:
        raise ScenarioError("scenario: empty string")
    fields = text.split("-")
    if len(fields) != len(FIELD_NAMES):
        raise ScenarioError(
            f"scenario: expected {len(FIELD_NAMES)} '-'-separated fields "
            f"({'-'.join(FIELD_NAMES)}), got {len(fields)} in {text!r}"
        )
    raw = dict(zip(FIELD_NAMES, fields))
    if raw["attacks"] == "benign":
        attacks: tuple = ()
    else:
        toks = raw["attacks"].split("+")
        if any(t == "" for t in toks):
            raise ScenarioError(f"field 'attacks': empty token in {raw['attacks']!r}")
        if "benign" in toks:
            raise ScenarioError("field 'attacks': 'benign' cannot be combined with attacks")
        attacks = tuple(_parse_attack(t) for t in toks)
        fams = [a.family for a in attacks]
        if len(set(fams)) != len(fams):
            raise ScenarioError(f"field 'attacks': a family appears twice in {raw['attacks']!r}")
        if {"dos", "ddos"} <= set(fams):
            raise ScenarioError("field 'attacks': dos and ddos cannot be combined (use ddos)")
    modulation = raw["modulation"]
    if modulation != "adaptive" and not _MCS.match(modulation):
        raise ScenarioError(
            f"field 'modulation': {modulation!r} is not 'adaptive' or a fixed level mcs0..mcs6"
        )
    n_uav = _int_field("n_uav", raw["n_uav"], 1, 250)
    if attacks and n_uav < 2:
        raise ScenarioError("field 'n_uav': an attack needs at least 2 UAVs (attacker + victim)")
    if any(a.family == "ddos" for a in attacks) and n_uav < 3:
        raise ScenarioError("field 'n_uav': ddos needs at least 3 UAVs (2 attackers + 1 victim)")
    sc = Scenario(
        attacks=attacks,
        n_uav=n_uav,
        n_bs=_int_field("n_bs", raw["n_bs"], 1, 16),
        payload=_choice("payload", raw["payload"], PAYLOADS),
        pathloss=_choice("pathloss", raw["pathloss"], PATHLOSS_MODELS),
        modulation=modulation,
        mission=_choice("mission", raw["mission"], MISSIONS),
        tx_dbm=_int_field("tx_dbm", raw["tx_dbm"], 0, 60),
        noise=_int_field("noise", raw["noise"], 30, 200),
    )
    if sc.to_string() != text:  # e.g. leading zeros are refused by _INT already; belt and braces
        raise ScenarioError(f"scenario: {text!r} is not in canonical form ({sc.to_string()!r})")
    return sc
