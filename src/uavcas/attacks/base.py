"""What an attack family is: one class owning every layer's rule for that family.

A family (`AttackFamily` subclass, one per module of this package, registered by name) owns
- its codec token and typed parameters (`spec`, `parse`),
- its schedule rule (`attackers`: who attacks, given the shared victim and the swarm),
- its executor on the kernel (`prepare`/`start`/`stop`/`calibrate`, plus routing hooks),
- its ground-truth rules (`effects`: which captured packets its attacks made, moved or dropped;
  `provoked`: which packets exist only because of those, e.g. the answers to a flood SYN; flows
  are labelled from their packets' effects, `uavcas.labels`),
- its recipe of synthetic flows (`synthetic_packets`, `synthetic_change`; `uavcas.dataset.synthetic`),
- its attack tool, if it runs one, beside it in `attacks/tools/` (a process the executor starts).

Its words (class string, packet effect and that effect's precedence, label source) are its row of
`uavcas.vocabulary.ROWS`, which `effect`, `label_source` and `class_name` read.

Layers outside this package ask the registry (`uavcas.attacks.family(name)`) and never test a
family name themselves. A family types against this module's protocols for what the layers above
hand it (`AttackExecutor`: the runner's executor, `emulation.attacks`; `TruthContext`: the
labeller's view of a run, `labels.effects`) and against the plan records (`uavcas.twin.model`),
which import no family; it imports the emulation's building blocks (kernel, apps) where it acts.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from collections.abc import Callable, Iterable
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any, ClassVar, Protocol

import numpy as np

from uavcas.scenario_model import ScenarioError, SpecBase
from uavcas.traffic.payloads import PAYLOAD_NAMES
from uavcas.vocabulary import FAMILY_ROWS, FamilyRow

if TYPE_CHECKING:
    from uavcas.emulation.apps.procs import Proc
    from uavcas.events import AttackRecord
    from uavcas.flows.packets import PacketTable
    from uavcas.labels.attacklog import AttackLog, AttackWindow
    from uavcas.network.forwarding import Detour
    from uavcas.twin.model import Attack, LinkOverride, Plan, Window


# One synthetic flow's packets (`uavcas.dataset.synthetic`), in time order: times (s from the flow's
# first packet), frame sizes (B), directions (0: from the flow's initiator, 1: back to it), TCP flags.
SyntheticPackets = tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]


class AttackExecutor(Protocol):
    """What a family's executor rules use of the runner's executor (`emulation.attacks`
    implements it): the running emulation, the attack log, per-attack state, the current window."""

    # the running `emulation.emulation.Emulation` (namespaces, switches, popen); typed Any because
    # that module reads plans through the registry, above this package
    emu: Any
    plan: Plan
    work_dir: Path
    log_dir: Path  # where attack processes write their logs
    duration_s: float
    active: dict[str, Attack]  # the attacks started and not yet halted, by id
    state: dict[str, Any]  # family-owned, keyed by attack id (or attack id/attacker)
    window: Window | None  # the window in force

    def ip(self, node: str) -> str: ...
    def index(self, node: str) -> int: ...
    def spec(self, a: Attack) -> SpecBase: ...
    def now(self) -> float: ...
    def log(self, rec: AttackRecord) -> AttackRecord: ...
    def add_process(self, proc: Proc, event_log: Path | None = None) -> None: ...
    def bs_of(self, uav: str) -> str: ...
    def reapply_window(self) -> dict[str, Any]: ...
    def reshape(self) -> None: ...


class Followed(Protocol):
    """The packet follower's answer (`flows.follow.Followed`) as the truth rules read it."""

    @property
    def pid(self) -> np.ndarray: ...  # per row, the transmission's id
    @property
    def hop(self) -> np.ndarray: ...  # per row, its hop along the transmission
    @property
    def points(self) -> tuple[str, ...]: ...  # capture points, as the packet table's
    @property
    def n_packets(self) -> int: ...
    @property
    def losses(self) -> Any: ...  # `flows.follow.Losses`
    def crossings(self) -> Any: ...  # `flows.follow.Crossings`


class TruthContext(Protocol):
    """What a family's effect rule may look at (`labels.effects.TruthContext` implements it): the
    run's packets, their transmissions, the attack log and the plan; masks are over packet rows."""

    packets: PacketTable
    log: AttackLog
    followed: Followed
    plan: Plan
    t0_unix: float

    @property
    def n(self) -> int: ...
    @property
    def ts(self) -> np.ndarray: ...
    @property
    def is_last(self) -> np.ndarray: ...
    @property
    def is_first(self) -> np.ndarray: ...
    @property
    def window(self) -> np.ndarray: ...  # plan window of each row
    @property
    def point_node(self) -> np.ndarray: ...  # per capture point, its node's plan index (-1: none)
    def packets_from(self, ips: Iterable[str]) -> np.ndarray: ...
    def packets_to(self, ips: Iterable[str]) -> np.ndarray: ...
    def touching(self, ips: Iterable[str]) -> np.ndarray: ...
    def during(self, start_unix: float, stop_unix: float) -> np.ndarray: ...
    def attacker_to_victim(self, windows: Iterable[AttackWindow], rows: np.ndarray) -> np.ndarray: ...
    def at_switch_of(self, names: Iterable[str]) -> np.ndarray: ...
    def node_names(self, ips: Iterable[str]) -> list[str]: ...
    def spread(self, rows: np.ndarray) -> np.ndarray: ...


class ScheduleDraw:
    """The state one schedule draw shares between the families of a composition."""

    def __init__(self, uav_names: list[str], victim: str, pool: list[str],
                 routes_start: dict[str, list[str]] | None, rng: np.random.Generator,
                 detours: Callable[[str, str], int] | None = None) -> None:
        self.uav_names, self.victim, self.pool = uav_names, victim, pool  # pool: seeded order
        self.routes_start = routes_start or {}
        self.rng = rng
        # windows of the attack in which a wormhole detour victim -> attacker -> BS exists
        self.detours = detours or (lambda victim, attacker: 1)
        self.used: set[str] = set()

    @property
    def n_uav(self) -> int:
        return len(self.uav_names)

    def take(self, k: int) -> list[str]:
        """k attackers, preferring UAVs no other family of this composition uses (reused only
        when the swarm is small), in node order."""
        fresh = [u for u in self.pool if u not in self.used]
        chosen = (fresh + [u for u in self.pool if u in self.used])[:k]
        self.used.update(chosen)
        return sorted(chosen, key=self.uav_names.index)


@dataclass(frozen=True)
class EmitterContext:
    """What placing a radio emitter may look at: the plan's pure inputs (no channel state)."""

    names: list[str]  # node names, plan order
    window_s: float
    positions_m: np.ndarray  # (windows, nodes, 3), metres, as Window.positions
    area_m: tuple[float, float, float, float]  # x_max, y_max, z_min, z_max
    rng: np.random.Generator  # the plan's emitter stream, shared by the attacks in schedule order


@dataclass(frozen=True)
class Emitter:
    """A transmitter an attack adds to the channel (a jammer), per plan window."""

    positions_m: np.ndarray  # (windows, 3)
    ground: bool  # a ground emitter (the ground end of its paths) or an airborne one
    eirp_dbm: float
    duty: float  # share of the time it transmits, (0, 1]


class AttackFamily(ABC):
    name: ClassVar[str]  # codec token and `Attack.family`: the token of its row in vocabulary.ROWS
    spec: ClassVar[type[SpecBase]]
    usage: ClassVar[str]  # the token's form, for error messages
    truth_rule: ClassVar[str]  # its effect rule in words (the dataset card records it)
    # its provoked rule in words (the dataset card records it next to truth_rule)
    provoked_rule: ClassVar[str] = "nothing"
    tools: ClassVar[tuple[str, ...]] = ()  # executables the executor needs on the host
    python_modules: ClassVar[tuple[str, ...]] = ()  # importable modules the executor needs
    min_uavs: ClassVar[int] = 2  # attacker(s) + victim
    routes_attack_traffic: ClassVar[bool] = False  # the plan routes attacker -> victim paths
    # families of one group cannot be combined in a composition (the floods: one flood per run)
    exclusive_group: ClassVar[str | None] = None
    detours_traffic: ClassVar[bool] = False  # the plan detours victim <-> BS through the attacker
    # the scenario payloads whose traffic the attack acts on (the codec refuses the others), and why
    payloads: ClassVar[tuple[str, ...]] = PAYLOAD_NAMES
    payloads_why: ClassVar[str] = ""

    # its row of the vocabulary: the words the family does not own alone -------------------------
    @property
    def row(self) -> FamilyRow:
        return FAMILY_ROWS[self.name]

    @property
    def effect(self) -> str:
        """The packet effect its truth rule gives (vocabulary.EFFECTS)."""
        return self.row.effect

    @property
    def label_source(self) -> str:
        """The label_source part of flows its truth rule marks (vocabulary.LABEL_SOURCES)."""
        return self.row.label_source

    @property
    def class_name(self) -> str:
        return self.row.class_name

    # codec -------------------------------------------------------------------------------------
    def parse(self, arg: str | None, tok: str) -> SpecBase:
        """The spec of token `tok` (`arg` is what follows '=', None without one)."""
        if arg is not None:
            raise ScenarioError(f"field 'attacks': {self.name} takes no value, got {tok!r}")
        return self.spec(family=self.name)

    def read_spec(self, data: Any) -> SpecBase:
        """The spec of a plan attack or scenario from its JSON form (a plan being read)."""
        return self.spec.model_validate(data)

    def spec_from_params(self, params: dict[str, Any]) -> SpecBase:
        """The spec of a plan attack written before attacks carried one (its `params`)."""
        return self.spec(family=self.name)

    # schedule ----------------------------------------------------------------------------------
    def params(self, spec: SpecBase) -> dict[str, float | int | str]:
        return spec.model_dump(exclude={"family"})

    def attackers(self, spec: SpecBase, draw: ScheduleDraw) -> list[str]:
        return draw.take(1)

    def emitter(self, attack: "Attack", ctx: EmitterContext) -> Emitter | None:
        """The radio emitter this attack places (the plan adds its interference to the links'
        noise floor while the attack lasts: `twin.interference`). Default: none."""
        return None

    def drawn_params(self, spec: SpecBase, draw: ScheduleDraw) -> dict[str, float | int | str]:
        """Parameters the schedule draws (seeded, from `draw.rng`, after `attackers`), recorded in
        the plan attack's `params` beside `params(spec)`. Default: none (no draw, so the schedules
        of the families that draw nothing do not change)."""
        return {}

    # executor ----------------------------------------------------------------------------------
    def calibration_times(self, attack: "Attack") -> list[float]:
        """Plan times (s) at which the runner calls `calibrate` during the attack."""
        return []

    def prepare(self, ex: "AttackExecutor", attack: "Attack") -> None:
        """Before t0 (processes that need time to start)."""

    @abstractmethod
    def start(self, ex: "AttackExecutor", attack: "Attack") -> dict[str, Any]:
        """Start the attack; returns the family's fields of the `start` record."""

    @abstractmethod
    def stop(self, ex: "AttackExecutor", attack: "Attack") -> dict[str, Any]:
        """Undo the attack completely; returns the family's fields of the `stop` record."""

    def halt(self, ex: "AttackExecutor", attack: "Attack") -> Callable[[], dict[str, Any]]:
        """The time-critical part of `stop`: when it returns the attack acts no more. Returns the
        rest (waiting for tools, reading counters, clean-up; it gives the `stop` record's
        fields), which the executor runs off the schedule's thread so that an event due at the
        same instant is not delayed by it. Default: all of `stop` now."""
        extra = self.stop(ex, attack)
        return lambda: extra

    def calibrate(self, ex: "AttackExecutor", attack: "Attack") -> None:
        pass

    def overrides(self, ex: "AttackExecutor", attack: "Attack", window: "Window") -> list["Detour"]:
        """Forwarding detours (`network.forwarding.Detour`) while the attack is active."""
        return []

    def shaping_overrides(self, ex: "AttackExecutor", attack: "Attack", window: "Window") -> list["LinkOverride"]:
        """Link directions shaped with other parameters than `window.links` give them while the
        attack is active (the runner applies them with every window, `AttackExecutor.reshape`
        when they change mid-window). Default: none."""
        return []

    # synthetic flows (`uavcas.dataset.synthetic`: no root, labels known by construction) -------
    def synthetic_packets(self, rng: np.random.Generator) -> SyntheticPackets | None:
        """The packets of a synthetic flow of a class holding this family, made by its attack in
        place of the benign-like packets the flow would otherwise have (a flood's SYNs), drawn from
        `rng`. Default None: the family makes no flow of its own."""
        return None

    def synthetic_change(self, rng: np.random.Generator, packets: SyntheticPackets, made: bool) -> SyntheticPackets:
        """What this family's attack does to a synthetic flow of a class holding it, drawn from
        `rng` (the families of the class change it in canonical order); `made`: the packets are
        another family's `synthetic_packets`, not benign-like. Default: nothing (such a family's
        flows are exactly benign-like: indistinguishable from Benign by construction)."""
        return packets

    # ground truth ------------------------------------------------------------------------------
    @abstractmethod
    def effects(self, ctx: "TruthContext", windows: list["AttackWindow"]) -> np.ndarray:
        """Boolean mask over the packet-table rows: the packets this family's attacks affected
        (every observation of an affected transmission: `ctx.spread`)."""

    def provoked(self, ctx: "TruthContext", windows: list["AttackWindow"], made: np.ndarray) -> np.ndarray:
        """Boolean mask over the packet-table rows: packets that exist only because of a packet
        in `made` (the rows this family's `effects` marked), matched packet to packet (header
        fields tying an answer to what it answers), never by hosts or time alone. They get the
        effect `provoked` with this family (`uavcas.labels.effects`). Default: nothing."""
        return np.zeros(ctx.n, dtype=bool)
