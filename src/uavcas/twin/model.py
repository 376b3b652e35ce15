"""Typed values of a plan: what the twin should do, per window.

A `Plan` is pure data. It is produced by `uavcas.twin.plan.plan()` without root or side effects and is
consumed by the emulator (`uavcas.emulation`), the labeller and the reports. Its JSON form
(`plan.json`) is the contract between those stages; `SCHEMA_VERSION` changes when it does.

The records import no attack family: an attack's spec is typed by the families' common base
(`uavcas.scenario_model.SpecBase`), and the family reads its own spec when a plan is read
(`uavcas.twin.load.read_plan`, the layer above that knows the registry).
"""

from __future__ import annotations

import re
from typing import Any, Literal

from pydantic import BaseModel, ConfigDict, Field, SerializeAsAny, ValidationInfo, model_validator

from uavcas.scenario_model import SPEC_READER, Scenario, SpecBase, read_spec, spec_reader
from uavcas.vocabulary import FAMILIES, Family

# 2: Plan.site and Node.sysid; 3: Window.interferers and link_overrides (jamming); 4: Plan.rounds (stored as
# "episodes"); 5: Plan.mavlink_stream_hz; defaults fill them in older plans
SCHEMA_VERSION = 5
# The telemetry stream rate a ground station requests of every autopilot (REQUEST_DATA_STREAM, all
# streams): MAVProxy's `streamrate` default (MAVProxy/mavproxy.py, MPSetting('streamrate', int, 4)).
# Plans made before it was recorded were run at this rate, so it is also their default.
DEFAULT_STREAM_HZ = 4
MAX_STREAM_HZ = 50

NodeKind = Literal["uav", "bs"]
LinkKind = Literal["air", "backhaul"]


class _Frozen(BaseModel):
    model_config = ConfigDict(frozen=True, extra="forbid")


_STANDARD_NAME = re.compile(r"^(uav|bs)(\d+)$")


def mavlink_sysid(kind: str, k: int) -> int:
    """UAV k -> MAVLink system id k + 1 (autopilots count from 1); BS k -> 255 - k (255 is the
    customary ground-station id: ArduPilot's SYSID_MYGCS default, MAVProxy's source system)."""
    return k + 1 if kind == "uav" else 255 - k


class Node(_Frozen):
    """One emulated host (a UAV or a base station) with its own stack and its own switch."""

    name: str  # "uav0".."uavN-1", "bs0".."bsM-1"
    kind: NodeKind
    index: int  # position in Plan.nodes; switch i belongs to node i
    ip: str  # IPv4 inside the emulation's private /16
    mac: str  # locally administered, derived from the index (static ARP/FDB need it up front)
    # MAVLink system id of the node's autopilot (UAV) or ground station (BS): `mavlink_sysid`.
    # None only for hand-made nodes whose name is not "uav<k>"/"bs<k>".
    sysid: int | None = Field(default=None, ge=1, le=255)

    @model_validator(mode="before")
    @classmethod
    def _sysid_from_name(cls, data: Any) -> Any:
        # plan.json of schema 1 and hand-made nodes: the id follows from the standard name
        if isinstance(data, dict) and data.get("sysid") is None and isinstance(data.get("name"), str):
            m = _STANDARD_NAME.match(data["name"])
            if m and m.group(1) == data.get("kind"):
                data = {**data, "sysid": mavlink_sysid(m.group(1), int(m.group(2)))}
        return data


class Site(_Frozen):
    """Where the plan's area lies on Earth: its origin (x = y = 0, z = 0) is this point, x east,
    y north, z up (metres above the site's ground). Coordinates on WGS-84.

    Default: the AERPAW Lake Wheeler LW1 tower (Raleigh, NC), lat/lon as the MPACT-Lab
    processing of the Maeng et al. LTE flights uses them (lat_BS/lon_BS of their
    data_gen/LTE_dataset script, uav-spectrum-sensing-insights); the same point is recovered
    to 3 mm from the published lat_s/lon_s/dist_2D_new_s columns of the data in
    ../shared/data/aerpaw. alt_m is 0: those data give altitudes above take-off only, no ground
    elevation, so the altitude MAVLink reports as AMSL equals the height above the site.
    """

    name: str = "AERPAW LW1"
    lat_deg: float = Field(default=35.727451, ge=-90.0, le=90.0)
    lon_deg: float = Field(default=-78.695974, ge=-180.0, le=180.0)
    alt_m: float = 0.0  # ground altitude of the origin above the WGS-84 ellipsoid (see above)


class Link(_Frozen):
    """An active undirected link in one window, with the parameters the channel chain gave it.

    `a` precedes `b` in node order. Air links carry the full chain; backhaul (BS-BS, wired) links
    have no radio fields. Rate, delay and loss apply to each direction independently.
    """

    a: str
    b: str
    kind: LinkKind
    distance_m: float
    pathloss_db: float | None
    snr_db: float | None
    mcs: int | None
    rate_mbps: float
    delay_ms: float
    loss: float = Field(ge=0.0, le=1.0)
    los: bool | None = None  # sampled LOS state where the path-loss model has one (3GPP)
    # A wormhole's detour link: up and shaped like any other, but forwarding uses it only for the
    # victim's own traffic while the attack is active (network.forwarding).
    detour: bool = False


class Route(_Frozen):
    """The hop-by-hop path a flow between two nodes takes in one window (node names, ends included).

    `disconnected`: no path over usable links joins the two this window (`hops` is then empty; the
    runner sends no benign traffic over it).
    """

    src: str
    dst: str
    hops: list[str]
    disconnected: bool = False


class Window(_Frozen):
    index: int
    t_s: float  # start of the window, seconds from the start of the run
    duration_s: float
    positions: dict[str, tuple[float, float, float]]  # metres, x/y in the area, z altitude
    links: list[Link]
    routes: list[Route]  # benign traffic paths (UAV i <-> BS i mod n_bs) and attack paths
    # Detours of wormholes active during any part of this window (links include their links, routes
    # do not). The runner switches a detour on and off at the attack's own start_s/stop_s.
    wormholes: list["WormholeOverride"] = Field(default_factory=list)
    # Transmitters outside the swarm (jammers) on during part of this window, and the link
    # directions whose parameters they change materially (`twin.interference`): `links` keep the
    # unjammed parameters, each override the jammed ones for [start_s, stop_s), which the runner
    # switches on and off at the attack's own start and stop.
    interferers: list["Interferer"] = Field(default_factory=list)
    link_overrides: list["LinkOverride"] = Field(default_factory=list)


class WormholeOverride(_Frozen):
    """While active, traffic between `victim` and `bs` (both directions) takes `hops`, victim ... bs,
    through `attacker`'s switch; no other traffic does."""

    victim: str
    attacker: str
    bs: str
    hops: list[str] = Field(default_factory=list)  # empty in plans written before detours had paths


class Interferer(_Frozen):
    """A transmitter that is no node of the swarm (a jammer), on the swarm's carrier, during
    [start_s, stop_s) of one window (plan seconds): where it is and what it sends."""

    attack_id: str
    position: tuple[float, float, float]  # metres, as Window.positions
    ground: bool  # on the ground (the ground end of its paths, as a BS) or airborne (a UAV end)
    eirp_dbm: float  # its antenna gain included
    duty: float = Field(gt=0.0, le=1.0)  # share of the time it transmits (pulsed; 1: continuous)
    fc_ghz: float = Field(gt=0.0)  # carrier: the swarm's own (the channel profile's)
    start_s: float
    stop_s: float


class LinkOverride(_Frozen):
    """The parameters direction src -> dst of one of the window's links holds during
    [start_s, stop_s) instead of the link's own (which stay as the unjammed plan): the attack's
    interference at the receiver dst, through the link's chain (`twin.interference`)."""

    attack_id: str
    src: str
    dst: str  # the receiver
    start_s: float
    stop_s: float
    interference_dbm: float  # the interferer's mean power at dst
    sinr_db: float  # the link's SNR with that power added to the noise floor
    mcs: int
    rate_mbps: float
    delay_ms: float
    loss: float = Field(ge=0.0, le=1.0)


class Attack(_Frozen):
    """One scheduled attack. Times are seconds from the start of the run; stop is exclusive."""

    attack_id: str  # stable within the plan: "<family>-<k>"
    family: Family
    attackers: list[str]
    victims: list[str]
    start_s: float
    stop_s: float
    params: dict[str, float | int | str] = Field(default_factory=dict)
    # the scenario's typed token of this family: its family's spec class, read from JSON by the
    # family (`uavcas.twin.load` passes the registry in as the validation context's SpecReader)
    spec: SerializeAsAny[SpecBase]

    @model_validator(mode="before")
    @classmethod
    def _read_spec(cls, data: Any, info: ValidationInfo) -> Any:
        if not (isinstance(data, dict) and data.get("family") in FAMILIES):
            return data
        what = f"attack {data.get('attack_id')}"
        if data.get("spec") is None:  # plan.json written before attacks carried their spec
            spec = spec_reader(info, what).spec_from_params(data["family"], data.get("params") or {})
            return {**data, "spec": spec}
        return {**data, "spec": read_spec(data["spec"], info, what)}

    @model_validator(mode="after")
    def _spec_matches(self) -> "Attack":
        if self.spec.family != self.family:
            raise ValueError(f"attack {self.attack_id}: spec of {self.spec.family!r} on a {self.family!r} attack")
        return self


class Plan(_Frozen):
    # fields are set by name in code and stored under their alias (`rounds` as "episodes")
    model_config = ConfigDict(frozen=True, extra="forbid", validate_by_name=True, validate_by_alias=True,
                              serialize_by_alias=True)

    schema_version: int = SCHEMA_VERSION
    config: str  # the scenario string, canonical form
    # Its typed axes and attack specs (None for hand-made plans whose config is no scenario).
    scenario: Scenario | None = None
    seed: int
    window_s: float
    # attack rounds drawn (`twin.schedule`): with seed, config and windows, it fixes the plan. Stored
    # as "episodes", its old name, so that plan.json stays byte-identical and old plans load.
    rounds: int = Field(default=1, ge=1, alias="episodes")
    profile: str  # channel/mobility profile name the plan was made with
    profile_sha256: str | None = None  # SHA-256 of the profile's JSON (None: plans made before it was recorded)
    area_m: tuple[float, float, float, float]  # x_max, y_max, z_min, z_max
    site: Site = Field(default_factory=Site)  # the area's origin on Earth (MAVLink positions)
    # MAVLink telemetry: the rate (Hz) the ground stations request of every stream (traffic/mavlink)
    mavlink_stream_hz: int = Field(default=DEFAULT_STREAM_HZ, ge=1, le=MAX_STREAM_HZ)
    nodes: list[Node]
    windows: list[Window]
    attacks: list[Attack]

    @model_validator(mode="before")
    @classmethod
    def _scenario_from_config(cls, data: Any, info: ValidationInfo) -> Any:
        # plan.json written before plans carried the typed scenario (read by the plan reader;
        # a plan built in code without one has none)
        reader = (info.context or {}).get(SPEC_READER)
        if reader is not None and isinstance(data, dict) and "scenario" not in data \
                and isinstance(data.get("config"), str):
            data = {**data, "scenario": reader.scenario(data["config"])}
        return data

    @property
    def duration_s(self) -> float:
        return len(self.windows) * self.window_s

    def node(self, name: str) -> Node:
        for n in self.nodes:
            if n.name == name:
                return n
        raise KeyError(f"no node named {name!r} in the plan")

    def disconnected_uavs(self, window: Window) -> list[str]:
        """UAVs whose route to a base station has no usable path in `window`."""
        kind = {n.name: n.kind for n in self.nodes}
        return [r.src for r in window.routes
                if r.disconnected and kind[r.src] == "uav" and kind[r.dst] == "bs"]

    @property
    def disconnected_fraction(self) -> float:
        """Share of UAV-windows in which the UAV reaches no base station."""
        n_uav = sum(n.kind == "uav" for n in self.nodes)
        total = n_uav * len(self.windows)
        return sum(len(self.disconnected_uavs(w)) for w in self.windows) / total if total else 0.0

    def to_json(self) -> str:
        """Byte-stable JSON: same plan, same bytes. Read back with `uavcas.twin.load.read_plan`."""
        return self.model_dump_json(indent=1) + "\n"


Window.model_rebuild()
