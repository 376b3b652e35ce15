"""Typed records of a run: the attack log (attacks.jsonl) and the runner's progress events.

attacks.jsonl has one JSON object per line, one record type per `event`:
- `start`: an attack began (t_unix taken just before the action; the blackhole's once its drop
  rule is in force), who and what;
- `stop`: it was fully undone (t_unix taken just after; the blackhole's just before its rule goes);
- `rate`: a flood attacker's measured SYN rate (logged before its `stop`);
- `inject`: one packet a replayer sent.
The emulation writes them, the labeller reads them; unknown or missing fields fail loudly
(extra="forbid"). The fields a family adds to its start/stop records are optional and written
only when set, so every family's lines read back exactly as they were written.
"""

from __future__ import annotations

from pathlib import Path
from typing import Annotated, Any, Literal, Union

from pydantic import BaseModel, ConfigDict, Field, TypeAdapter, ValidationError

from uavcas.vocabulary import Family


class _Record(BaseModel):
    model_config = ConfigDict(frozen=True, extra="forbid")

    def to_line(self) -> str:
        """One JSON line: the tag, every field set, and none of the optional ones left unset."""
        tags = {"event", "kind"} & set(type(self).model_fields)
        return self.model_dump_json(include=set(self.model_fields_set) | tags) + "\n"


class AttackStart(_Record):
    event: Literal["start"] = "start"
    attack_id: str
    family: Family
    attackers: list[str]
    attacker_ips: list[str]
    victims: list[str]
    victim_ips: list[str]
    t_unix: float
    params: dict[str, float | int | str]
    planned_start_s: float
    planned_stop_s: float
    # Family details (see uavcas.attacks.<family>.start).
    hping_interval_us: list[int] | None = None  # floods: per attacker
    switch: list[str] | None = None  # blackhole: the victims' bridges
    fdb_changes: int | None = None  # wormhole: forwarding entries changed
    paths: dict[str, list[str] | None] | None = None  # wormhole: "victim>bs" -> the path now
    rejected: list[str] | None = None  # wormhole: overrides the controller refused
    mirror: dict[str, str | list[str]] | None = None  # replay: {"from": port, "to": [ports]}
    jammed: list[str] | None = None  # jamming: the link directions "src>dst" it reshaped now
    shaping_from_unix: float | None = None  # jamming: when the reshape began (in force at t_unix)


class AttackStop(_Record):
    event: Literal["stop"] = "stop"
    attack_id: str
    family: Family
    t_unix: float
    syn_count: int | None = None  # floods
    dropped_frames: int | None = None  # blackhole
    fdb_changes: int | None = None  # wormhole
    paths: dict[str, list[str] | None] | None = None
    rejected: list[str] | None = None
    replayer_stats: dict[str, dict[str, Any] | None] | None = None  # replay: per attacker
    shaping_until_unix: float | None = None  # jamming: when the unjammed shaping was back
    commands_sent: int | None = None  # mavlink_inject: forged commands that left the attackers
    commands_acked: int | None = None  # mavlink_inject: COMMAND_ACKs the attackers received
    # floods and mavlink_inject: t_unix is when the last packet left an attacker; this is when it
    # can have crossed the network (a bound: each hop's delay plus a full queue), so that every
    # observation of the attack's packets lies inside [start, crossed_unix)
    crossed_unix: float | None = None


class AttackRate(_Record):
    event: Literal["rate"] = "rate"
    attack_id: str
    family: Family
    attacker: str
    measured_pps: float
    nominal_pps: float
    hping_interval_us: int
    syn_count: int
    seconds: float
    restarts: int
    intervals_us: list[int]
    victim_ip: str
    t_unix: float


class Inject(_Record):
    event: Literal["inject"] = "inject"
    attack_id: str
    family: Family
    t_unix: float
    src_ip: str
    dst_ip: str
    src_port: int | None
    dst_port: int | None
    protocol: int
    ip_id: int
    ttl: int
    seq: int | None  # TCP only
    orig_seq: int | None
    orig_ttl: int


AttackRecord = Annotated[Union[AttackStart, AttackStop, AttackRate, Inject], Field(discriminator="event")]
_RECORD = TypeAdapter(AttackRecord)


class RecordError(ValueError):
    """A malformed record; the message is one line and names the file, the line and the field."""


def _explain(err: ValidationError) -> str:
    e = err.errors()[0]
    loc = ".".join(str(x) for x in e["loc"][1:] or e["loc"])
    if e["type"] == "missing":
        return f"record has no '{loc}'"
    if e["type"] == "extra_forbidden":
        return f"unknown field '{loc}'"
    if e["type"] == "union_tag_invalid" or (e["type"] == "union_tag_not_found"):
        return f"unknown or missing event ({e['msg']})"
    return f"bad field value '{loc}' ({e['msg']})"


def parse_attack_record(line: str, where: str) -> AttackRecord:
    try:
        return _RECORD.validate_json(line)
    except ValidationError as err:
        if err.errors()[0]["type"] == "json_invalid":
            raise RecordError(f"{where}: not JSON ({err.errors()[0]['msg']})") from None
        raise RecordError(f"{where}: {_explain(err)}") from None


def read_attack_records(path: Path) -> list[AttackRecord]:
    """Every record of an attacks.jsonl-style file (blank lines skipped)."""
    out = []
    for lineno, line in enumerate(Path(path).read_text().splitlines(), 1):
        if line.strip():
            out.append(parse_attack_record(line, f"{path}:{lineno}"))
    return out


def attack_log_text(records: list[AttackRecord]) -> str:
    return "".join(r.to_line() for r in records)


# Progress events the runner emits while it plays a plan (the CLI shows them) -----------------------
class SetupDone(_Record):
    kind: Literal["setup"] = "setup"
    prefix: str
    seconds: float


class WindowApplied(_Record):
    kind: Literal["window"] = "window"
    window: int
    n_windows: int
    t0_unix: float | None = None  # set on window 0: the run's t0


class AttackLogged(_Record):
    kind: Literal["attack"] = "attack"
    record: AttackRecord


class RunDone(_Record):
    kind: Literal["done"] = "done"
    exit_status: int
    reason: str


Progress = Union[SetupDone, WindowApplied, AttackLogged, RunDone]
