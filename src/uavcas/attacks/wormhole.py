"""Wormhole: the victim's traffic with its BS is tunnelled through the attacker's switch.

- token `wormhole` (no parameters);
- schedule: the attacker is drawn among UAVs off the victim's route at t = 0 that have a detour
  then (a usable link to the victim, and a usable path to the victim's BS not through it), so the
  detour really adds a hop and really carries traffic;
- plan: in each window the attack overlaps, the planner adds the detour's links where it has one
  (`detours_traffic`, `topology.routing.with_wormholes`: usable links only; a window without
  one gets no override) and lists it, with its hops, in `Window.wormholes`;
- executor: at start the current window is re-applied with the detour: both directions of the
  victim <-> BS traffic (the victim's MAC as source or destination) take the detour's hops
  through the attacker's switch, and nothing else does (alias destination MACs, see
  `emulation.controller`); at stop it is re-applied without. The detour's links are the plan's,
  shaped like any other;
- truth: see `Wormhole.effects`."""

from __future__ import annotations

from typing import TYPE_CHECKING, Any, Literal

import numpy as np

from .base import AttackFamily, ScheduleDraw, SpecBase
from .registry import register

if TYPE_CHECKING:
    from uavcas.emulation.attacks import AttackExecutor
    from uavcas.emulation.controller import Detour
    from uavcas.labels.attacklog import AttackWindow
    from uavcas.labels.label import TruthContext
    from uavcas.twin.model import Attack, Window


class WormholeSpec(SpecBase):
    family: Literal["wormhole"] = "wormhole"


@register
class Wormhole(AttackFamily):
    name = "wormhole"
    spec = WormholeSpec
    usage = "wormhole"
    label_source = "victim-window"
    detours_traffic = True

    def attackers(self, spec: SpecBase, draw: ScheduleDraw) -> list[str]:
        on_path = set(draw.routes0.get(draw.victim, ()))
        off = [u for u in draw.pool if u not in draw.used and u not in on_path]
        able = [u for u in off if draw.detour0(draw.victim, u)]
        attackers = [(able or off)[0]] if off else draw.take(1)
        draw.used.update(attackers)
        return attackers

    def start(self, ex: "AttackExecutor", attack: "Attack") -> dict[str, Any]:
        ex.active[attack.attack_id] = attack  # the overrides must see it before the FDB is rebuilt
        return ex.reapply_window()

    def stop(self, ex: "AttackExecutor", attack: "Attack") -> dict[str, Any]:
        del ex.active[attack.attack_id]
        return ex.reapply_window()

    def overrides(self, ex: "AttackExecutor", attack: "Attack", window: "Window") -> list["Detour"]:
        from uavcas.emulation.controller import Detour

        return [Detour(o.victim, o.attacker, o.bs, tuple(o.hops)) for o in window.wormholes
                if o.victim in attack.victims and o.attacker in attack.attackers]

    def truth(self, ctx: "TruthContext", windows: list["AttackWindow"]) -> np.ndarray:
        return ctx.victim_window(windows)
