"""MAVLink command injection: an attacker sends the victim's autopilot forged ground-station commands.

- token `mavlink_inject=<rtl|land|speed>[,mps=<m/s>][,hz=<Hz>][,n=<count>]` (only the values
  that differ from the defaults are written): the command forged, MAV_CMD_NAV_RETURN_TO_LAUNCH,
  MAV_CMD_NAV_LAND or MAV_CMD_DO_CHANGE_SPEED with `mps` m/s (speed only; default 20 m/s,
  ArduCopter's largest WPNAV_SPEED, 2000 cm/s: the attacker pushes the vehicle to its limit),
  sent `hz` times a second (default 2: the ground station's own command retry period, 0.5 s,
  MAVSDK's timeout) until `n` have left (default 0: no limit, the attacker re-asserts its
  command for the whole attack, so the ground station's per-window DO_CHANGE_SPEED cannot
  undo a forged speed for long and a frame lost on the channel is repeated). Only payloads that
  carry MAVLink (telemetry, video, mixed); the codec refuses it on `image` in one line;
- schedule: one attacker (a UAV of the swarm), the composition's victim;
- executor: one `attacks.tools.mavinject` per attacker, started before t0 (pymavlink's load)
  and waiting for its go file: COMMAND_LONG frames packed by pymavlink with the victim's ground
  station's system id and component id (MAV_COMP_ID_MISSIONPLANNER, 190), targeting the
  victim's autopilot, MAVLink 2 and unsigned (the attacker has no key), from one ephemeral UDP
  port to the autopilot's fixed port (`traffic.mavlink.specs.UAV_PORT`). The start is logged
  before the go file is written (no frame leaves before it); `halt` signals the injector, whose
  handler exits at once (after the frame being sent, if any); the stop is logged, off the
  schedule's thread, at the time it had exited, with `crossed_unix` when its last frame can have
  crossed the network (the flood's `quiet_after_s` over the attacker -> victim path), the frames
  sent and the COMMAND_ACKs received. The victim's autopilot
  (`traffic.mavlink.commands`) accepts and acknowledges RTL / LAND (its HEARTBEAT's custom_mode
  becomes 6 / 9) and DO_CHANGE_SPEED, unless the run signs MAVLink (`--mavlink-signing`,
  `traffic.mavlink.signing`): then it drops the unsigned frames unanswered;
- truth (effect `mavlink_inject`, label source "mavlink-injections"): a UDP packet from an
  attacker's IP to a victim's IP and the autopilot's MAVLink port, captured inside
  [start, crossed) of the attack (every observation of its transmission). Benign MAVLink flows between a UAV and
  its BS only: no benign UAV sends to another UAV's MAVLink port, so the header facts and the
  logged window single out the forged frames, whether the victim accepts them or not;
- provoked (effect `provoked` with this family): what exists only because of a forged frame,
  matched to it packet to packet (`attacks.answers`), after it and within ANSWER_WITHIN_S:
  (a) the victim's answers, its COMMAND_ACKs: UDP on the forged frame's 5-tuple reversed (from
      the victim's MAVLink port to the attacker's ephemeral port, which carries nothing else);
  (b) ICMP errors to the attacker quoting a forged frame (e.g. port unreachable).
  With signing on there is no answer, so nothing is provoked.
"""

from __future__ import annotations

import signal
import sys
from collections.abc import Callable
from typing import TYPE_CHECKING, Any, Literal

import numpy as np
from pydantic import Field

from uavcas.emulation.apps.procs import spawn, wait_for
from uavcas.scenario_model import ScenarioError, SpecBase, choice, int_field
from uavcas.traffic.apps import MAVLINK_PAYLOADS
from uavcas.traffic.mavlink.specs import UAV_PORT

from .answers import ANSWER_WITHIN_S, icmp_errors_quoting, udp_answers
from .base import AttackExecutor, AttackFamily, TruthContext
from .flood import path_hops
from .registry import register
from .tools import tool_path
from .tools.flood import quiet_after_s
from .tools.mavinject import read_log

if TYPE_CHECKING:  # types only: the twin's and labels' package __init__s load this registry
    from uavcas.labels.attacklog import AttackWindow
    from uavcas.twin.model import Attack

COMMANDS: tuple[str, ...] = ("rtl", "land", "speed")
DEFAULT_SPEED_MPS = 20  # ArduCopter WPNAV_SPEED's upper bound, 2000 cm/s
DEFAULT_RATE_HZ = 2  # the ground station's command retry period, 0.5 s (traffic.mavlink.specs.RetrySpec)
DEFAULT_COUNT = 0  # no limit: the whole attack
READY_S = 30.0  # the injector's start-up (Python + pymavlink in a busy namespace) must finish within this
_KEYS = {"mps": "speed_mps", "hz": "rate_hz", "n": "count"}


class MavlinkInjectSpec(SpecBase):
    family: Literal["mavlink_inject"] = "mavlink_inject"
    command: Literal["rtl", "land", "speed"]
    speed_mps: int | None = Field(default=None, ge=0, le=50)  # DO_CHANGE_SPEED's param2; speed only
    rate_hz: int = Field(default=DEFAULT_RATE_HZ, ge=1, le=100)
    count: int = Field(default=DEFAULT_COUNT, ge=0, le=1_000_000)  # frames per attacker, 0: no limit

    def token(self) -> str:
        parts = [self.command]
        if self.command == "speed" and self.speed_mps != DEFAULT_SPEED_MPS:
            parts.append(f"mps={self.speed_mps}")
        if self.rate_hz != DEFAULT_RATE_HZ:
            parts.append(f"hz={self.rate_hz}")
        if self.count != DEFAULT_COUNT:
            parts.append(f"n={self.count}")
        return "mavlink_inject=" + ",".join(parts)


@register
class MavlinkInject(AttackFamily):
    name = "mavlink_inject"
    spec = MavlinkInjectSpec
    usage = "mavlink_inject=<rtl|land|speed>[,mps=<m/s>][,hz=<Hz>][,n=<count>]"
    truth_rule = ("a UDP packet from an attacker to a victim's MAVLink port (the autopilot's, 14550) captured "
                  "inside [start, stop) (a forged COMMAND_LONG)")
    provoked_rule = ("the victim's answers to a forged frame (its COMMAND_ACKs) on the frame's UDP 5-tuple reversed, "
                     f"and ICMP errors quoting the frame, each within {ANSWER_WITHIN_S:g} s after it")
    python_modules = ("pymavlink",)
    routes_attack_traffic = True  # the attacker -> victim path must exist in the forwarding
    payloads = MAVLINK_PAYLOADS
    payloads_why = "it forges MAVLink commands, which image traffic does not carry"

    def parse(self, arg: str | None, tok: str) -> MavlinkInjectSpec:
        if not arg:
            raise ScenarioError("field 'attacks': mavlink_inject needs a command, e.g. mavlink_inject=rtl "
                                f"({self.usage})")
        command, *rest = arg.split(",")
        kw: dict[str, Any] = {"command": choice("attacks.mavlink_inject.command", command, COMMANDS)}
        for part in rest:
            key, eq, raw = part.partition("=")
            if not eq or key not in _KEYS:
                raise ScenarioError(f"field 'attacks': {part!r} in {tok!r} is not one of mps=, hz=, n= ({self.usage})")
            if _KEYS[key] in kw:
                raise ScenarioError(f"field 'attacks': {key}= given twice in {tok!r}")
            if key == "mps" and command != "speed":
                raise ScenarioError(f"field 'attacks': mps= applies to the speed command only, got {tok!r}")
            lo, hi = {"mps": (0, 50), "hz": (1, 100), "n": (0, 1_000_000)}[key]
            kw[_KEYS[key]] = int_field(f"attacks.mavlink_inject.{key}", raw, lo, hi)
        if command == "speed":
            kw.setdefault("speed_mps", DEFAULT_SPEED_MPS)
        return MavlinkInjectSpec(**kw)

    def spec_from_params(self, params: dict[str, Any]) -> MavlinkInjectSpec:
        return MavlinkInjectSpec(**{k: params[k] for k in ("command", "speed_mps", "rate_hz", "count") if k in params})

    def params(self, spec: MavlinkInjectSpec) -> dict[str, float | int | str]:  # type: ignore[override]
        return spec.model_dump(exclude={"family"}, exclude_none=True)

    # executor ----------------------------------------------------------------------------------
    def prepare(self, ex: "AttackExecutor", attack: "Attack") -> None:
        s: MavlinkInjectSpec = ex.spec(attack)  # type: ignore[assignment]
        v = attack.victims[0]
        gcs = ex.plan.node(ex.bs_of(v))
        if gcs.sysid is None or ex.plan.node(v).sysid is None:
            raise RuntimeError(f"{attack.attack_id}: the plan has no MAVLink system ids for {v} and {gcs.name}")
        procs = {}
        for x in attack.attackers:
            stem = ex.log_dir / f"mavinject-{attack.attack_id}-{x}"
            stem.parent.mkdir(parents=True, exist_ok=True)
            go, log = stem.with_suffix(".go"), stem.with_suffix(".jsonl")
            go.unlink(missing_ok=True)
            log.write_text("")
            argv = [sys.executable, str(tool_path("mavinject")), "--victim-ip", ex.ip(v),
                    "--target-sysid", str(ex.plan.node(v).sysid), "--gcs-sysid", str(gcs.sysid),
                    "--command", s.command, "--speed-mps", str(float(s.speed_mps or 0)),
                    "--rate-hz", str(float(s.rate_hz)), "--count", str(s.count), "--go", str(go),
                    "--log", str(log), "--seconds", str(ex.duration_s + 30)]
            proc = spawn(lambda av, t, _x=x, **kw: ex.emu.popen(_x, av, t, **kw), f"mavinject-{attack.attack_id}-{x}",
                         argv, ex.log_dir, ex.duration_s + 40)
            ex.add_process(proc)
            procs[x] = (proc, go, log)
        ex.state[attack.attack_id] = procs
        for x, (proc, _, _) in procs.items():
            if not wait_for(lambda: "ready" in proc.stdout() or not proc.alive(), READY_S, 0.05) or not proc.alive():
                raise RuntimeError(f"{attack.attack_id}: injector on {x} did not start: {proc.stderr().strip()[-300:]}")

    def start(self, ex: "AttackExecutor", attack: "Attack") -> dict[str, Any]:
        procs = ex.state[attack.attack_id]
        for x, (proc, _, _) in procs.items():
            if not proc.alive():
                raise RuntimeError(f"injector on {x} is not running: {proc.stderr().strip()[-300:]}")
        t = ex.now()  # before any go file exists: no forged frame leaves before it
        for _, go, _ in procs.values():
            go.touch()
        return {"t_unix": t}

    def stop(self, ex: "AttackExecutor", attack: "Attack") -> dict[str, Any]:
        return self.halt(ex, attack)()

    def halt(self, ex: "AttackExecutor", attack: "Attack") -> Callable[[], dict[str, Any]]:
        procs = ex.state.pop(attack.attack_id, {})
        for proc, _, _ in procs.values():  # its handler exits at once (after the frame being sent, if any)
            if proc.alive():
                proc.popen.send_signal(signal.SIGTERM)

        def finish() -> dict[str, Any]:
            for proc, _, _ in procs.values():
                proc.stop(signal.SIGTERM, grace_s=2.0)  # returns when the injector has exited
            t_closed = ex.now()
            counts = [read_log(log) for _, _, log in procs.values()]
            # no frame left an attacker after t_closed; the last ones may still be crossing the network
            quiet = max((quiet_after_s(path_hops(ex, x, v)) for x in attack.attackers for v in attack.victims),
                        default=0.0)
            return {"t_unix": t_closed, "crossed_unix": t_closed + quiet, "commands_sent": sum(c[0] for c in counts),
                    "commands_acked": sum(c[1] for c in counts)}

        return finish

    # ground truth ------------------------------------------------------------------------------
    def effects(self, ctx: "TruthContext", windows: list["AttackWindow"]) -> np.ndarray:
        p = ctx.packets
        to_autopilot = (p["proto"] == 17) & (p["dport"] == UAV_PORT)
        return ctx.spread(ctx.attacker_to_victim(windows, to_autopilot))

    def provoked(self, ctx: "TruthContext", windows: list["AttackWindow"], made: np.ndarray) -> np.ndarray:
        p = ctx.packets
        hit = udp_answers(p, made, np.ones(ctx.n, dtype=bool)) | icmp_errors_quoting(p, made)
        return ctx.spread(hit) & ~made
