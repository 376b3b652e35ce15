"""A run directory, typed: its paths (`RunDir`) and its run.json (`RunInfo`).

    RUN_DIR/.uavcas-run     written first: which run owns the directory (RunOwner)
    RUN_DIR/plan.json       the Plan played (twin.model.Plan)
    RUN_DIR/run.json        what happened (RunInfo), written last
    RUN_DIR/attacks.jsonl   the attack log (uavcas.events records)
    RUN_DIR/shaping.jsonl   per-window shaping records of every link
    RUN_DIR/forwarding.jsonl  every forwarding table installed, with when (ForwardingEpoch)
    RUN_DIR/fidelity.json   the fidelity audit (uavcas.fidelity.Fidelity), summarised in run.json
    RUN_DIR/pcap/           one capture per switch
    RUN_DIR/logs/           tool logs (curl results, stderr)

Written by the emulation (`emulation.runner`), read by labels, dataset and the CLI. Unknown or
missing fields of run.json fail loudly (extra="forbid").
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Literal

from pydantic import BaseModel, ConfigDict, ValidationError

from uavcas.atomic import atomic_write_text
from uavcas.events import AttackRecord, RecordError, read_attack_records
from uavcas.twin.load import read_plan
from uavcas.twin.model import Plan

CAPTURE_SUFFIXES = (".pcap", ".pcapng")


class RunDirError(ValueError):
    """A run directory or one of its files that cannot be used; one-line message."""


class _Strict(BaseModel):
    model_config = ConfigDict(frozen=True, extra="forbid")


class Lateness(_Strict):
    max: float
    mean: float


class Timings(_Strict):
    """Seconds per phase of the run (phases an interrupted run never reached are absent)."""

    setup_s: float | None = None
    apps_s: float | None = None
    schedule_s: float | None = None
    stop_s: float | None = None
    teardown_s: float | None = None
    links_ready_s: float | None = None  # window 0's links raised and operational, before t0
    schedule_lateness_ms: Lateness | None = None


class WindowApply(_Strict):
    window: int
    t_unix: float
    links_up: int
    links_down: int
    fdb_changes: int
    rejected: list[str]
    timings_s: dict[str, float]


class ScheduledEvent(_Strict):
    t_s: float
    kind: str  # window, start, stop, calibrate, end; prepare: the next window's links raised ahead
    what: str | int | None  # the attack id, or the window index
    late_ms: float
    took_ms: float


class CaptureRecord(_Strict):
    """One switch's tcpdump, as `uavcas.emulation.apps.capture` reports it."""

    point: str
    path: str
    captured: int | None
    received_by_filter: int | None
    dropped_by_kernel: int | None
    dropped_by_interface: int | None
    size_bytes: int
    exit_code: int | None


class ForwardingEpoch(_Strict):
    """One line of forwarding.jsonl: a forwarding table the fabric held from `t_unix` on.

    The switches changed over between `t_begin_unix` (the apply began) and `t_unix` (it ended);
    in between a frame may have met either table. `next_hop[switch][destination]` is the
    neighbour switch (node names) a frame for `destination` leaves `switch` towards; a missing
    entry means the switch had no way there (the frame is dropped).

    `detours["victim>bs"]`: the switches a wormhole detour carries the victim's frames to bs
    through (victim first), and bs's frames back in reverse, on alias MACs outside `next_hop`
    (`network.forwarding`); absent in runs made before detours were logged.
    """

    t_begin_unix: float
    t_unix: float
    window: int
    next_hop: dict[str, dict[str, str]]
    detours: dict[str, list[str]] = {}


class FidelitySummary(_Strict):
    """What run.json keeps of the run's fidelity audit (fidelity.json holds all of it)."""

    verdict: Literal["pass", "fail", "error"]  # error: the audit itself could not be made
    failed: list[str]  # the checks that failed
    delay_error_p50_ms: float | None = None
    delay_error_p90_ms: float | None = None
    delay_error_p99_ms: float | None = None
    error: str | None = None


class RunInfo(_Strict):
    """run.json: the run's identity, outcome, environment and measurements."""

    config: str
    seed: int
    windows: int
    window_s: float
    prefix: str | None
    t0_unix: float | None  # wall-clock time of plan t = 0 (None: the run never got there)
    t_end_unix: float
    wall_s: float
    exit_status: int  # 0 ok, 130 SIGINT, 128+n other signals, 1 error
    exit_reason: str
    versions: dict[str, str | None]
    tool_versions: dict[str, str | None]
    kernel: str
    kernel_features: dict[str, Any] | None
    shaper_backend: str | None
    timings: Timings
    window_applies: list[WindowApply]
    schedule: list[ScheduledEvent]
    capture: list[CaptureRecord]  # per switch
    capture_drops: int | None
    packets_captured: int
    http_clients: list[dict[str, Any]]  # per BS client: the image app's results (uavcas.traffic.apps.image)
    # per traffic app with a section (mavlink, video), its outcome by app name
    # (uavcas.traffic.benign.BenignTraffic.streams_summary); None: no app of the payload has one (image)
    streams: dict[str, Any] | None = None
    delay_daemon: dict[str, Any] | None
    attack_errors: list[str]
    wind_down_errors: list[str]
    run_id: str | None = None  # set by whoever names runs (e.g. a campaign); else the dir's name
    profile: str | None = None  # twin profile of the plan (plan.json has it too) and its SHA-256
    profile_sha256: str | None = None
    fidelity: FidelitySummary | None = None  # set by the audit (uavcas.fidelity), None: not audited
    mavlink_signing: bool = False  # the MAVLink endpoints signed their messages (MAVLink 2 signing)

    def to_json(self) -> str:
        return self.model_dump_json(indent=1, exclude_none=False) + "\n"


class RunOwner(_Strict):
    """.uavcas-run: written before anything else of a run, so a directory a run was killed in
    (no run.json yet) is still known for a uavcas run's, and whose (its namespace prefix)."""

    prefix: str
    pid: int
    started_unix: float
    t0_unix: float | None = None  # plan t = 0, written once the run gets there (a killed run keeps it)


@dataclass(frozen=True)
class RunDir:
    root: Path

    # the small files of a run
    FILES = ("plan.json", "run.json", "attacks.jsonl", "shaping.jsonl", "forwarding.jsonl", "fidelity.json")
    OWNER = ".uavcas-run"

    def __post_init__(self) -> None:
        object.__setattr__(self, "root", Path(self.root))

    @property
    def plan_json(self) -> Path:
        return self.root / "plan.json"

    @property
    def run_json(self) -> Path:
        return self.root / "run.json"

    @property
    def attacks_jsonl(self) -> Path:
        return self.root / "attacks.jsonl"

    @property
    def shaping_jsonl(self) -> Path:
        return self.root / "shaping.jsonl"

    @property
    def pcap_dir(self) -> Path:
        return self.root / "pcap"

    @property
    def logs_dir(self) -> Path:
        return self.root / "logs"

    def files(self) -> list[Path]:
        return [self.root / f for f in self.FILES]

    @property
    def owner_path(self) -> Path:
        return self.root / self.OWNER

    def read_t0(self) -> float | None:
        """Wall-clock time of plan t = 0: run.json's, else (a killed run) the marker's; None when
        the run never got there."""
        info = self.read_info()
        if info is not None:
            return info.t0_unix
        owner = self.read_owner()
        return owner.t0_unix if owner is not None else None

    def write_owner(self, owner: RunOwner) -> None:
        atomic_write_text(self.owner_path, owner.model_dump_json() + "\n")

    def read_owner(self) -> RunOwner | None:
        """The run that owns this directory (None: no marker, e.g. a run older than the marker)."""
        if not self.owner_path.exists():
            return None
        try:
            return RunOwner.model_validate_json(self.owner_path.read_text())
        except ValidationError:
            raise RunDirError(f"{self.owner_path}: not a uavcas run marker") from None

    @property
    def fidelity_json(self) -> Path:
        return self.root / "fidelity.json"

    @property
    def forwarding_jsonl(self) -> Path:
        return self.root / "forwarding.jsonl"

    def pcaps(self) -> list[Path]:
        return sorted(p for p in self.pcap_dir.glob("*") if p.suffix in CAPTURE_SUFFIXES)

    def read_plan(self) -> Plan:
        if not self.plan_json.exists():
            raise RunDirError(f"{self.root}: no plan.json (not a run directory)")
        try:
            return read_plan(self.plan_json.read_text())
        except ValueError as exc:
            raise RunDirError(f"{self.plan_json}: invalid plan ({str(exc).splitlines()[0]})") from None

    def read_info(self) -> RunInfo | None:
        """run.json, or None when the run never wrote one."""
        if not self.run_json.exists():
            return None
        try:
            return RunInfo.model_validate_json(self.run_json.read_text())
        except ValidationError as exc:
            e = exc.errors()[0]
            loc = ".".join(str(x) for x in e["loc"])
            if e["type"] == "json_invalid":
                raise RunDirError(f"{self.run_json}: not JSON ({e['msg']})") from None
            what = {"missing": "has no field", "extra_forbidden": "has an unknown field"}.get(e["type"], "bad field")
            raise RunDirError(f"{self.run_json}: {what} '{loc}' ({e['msg']})") from None

    def read_attacks(self) -> list[AttackRecord]:
        """The attack log ([] when absent: a benign run, or one that crashed before writing it)."""
        if not self.attacks_jsonl.exists():
            return []
        try:
            return read_attack_records(self.attacks_jsonl)
        except RecordError as exc:
            raise RunDirError(str(exc)) from None

    def read_shaping(self) -> list[dict[str, Any]]:
        if not self.shaping_jsonl.exists():
            return []
        return [json.loads(ln) for ln in self.shaping_jsonl.read_text().splitlines() if ln.strip()]

    def read_forwarding(self) -> list[ForwardingEpoch]:
        """The forwarding tables the run installed ([] for runs made before they were logged)."""
        if not self.forwarding_jsonl.exists():
            return []
        out = []
        for lineno, ln in enumerate(self.forwarding_jsonl.read_text().splitlines(), 1):
            if not ln.strip():
                continue
            try:
                out.append(ForwardingEpoch.model_validate_json(ln))
            except ValidationError as exc:
                raise RunDirError(f"{self.forwarding_jsonl}:{lineno}: {exc.errors()[0]['msg']}") from None
        return out
