"""Wormhole: the victim's traffic to its BS is tunnelled through the attacker's switch.

- token `wormhole` (no parameters);
- schedule: the attacker is drawn among UAVs off the victim's route at t = 0 where possible, so
  the detour really adds a hop instead of re-labelling a path the traffic took anyway;
- plan: while the attack overlaps a window, the planner adds the detour's links and routes
  (`detours_traffic`, `topology.routing.with_wormholes`) and lists the override in
  `Window.wormholes`;
- executor: the override (victim <-> its BS through the attacker's switch) is laid into the
  static FDB at start and removed at stop, by re-applying the current window with the active
  overrides. The detour's links are the plan's, so the extra hop is shaped like any other;
  while the attack is idle the pair takes the shortest path avoiding the attacker's switch;
- truth ("victim-window"): a flow to or from a victim IP whose lifetime overlaps [start, stop).
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any, Literal

import numpy as np

from .base import AttackFamily, ScheduleDraw, SpecBase
from .registry import register

if TYPE_CHECKING:
    from uavcas.emulation.attacks import AttackExecutor
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

    def overrides(self, ex: "AttackExecutor", attack: "Attack", window: "Window") -> list[tuple[str, str, str]]:
        out: list[tuple[str, str, str]] = []
        for v in attack.victims:
            planned = [(o.victim, o.attacker, o.bs) for o in window.wormholes
                       if o.victim == v and o.attacker in attack.attackers]
            out += planned or [(v, attack.attackers[0], ex.bs_of(v))]
        return out

    def idle_routes(self, ex: "AttackExecutor", attack: "Attack", window: "Window",
                    adj: dict[str, list[str]]) -> dict[tuple[str, str], list[str] | None]:
        from uavcas.emulation.controller import shortest_path

        out: dict[tuple[str, str], list[str] | None] = {}
        for v in attack.victims:
            b = ex.bs_of(v)
            path = shortest_path(adj, v, b, banned=frozenset(attack.attackers))
            out[(v, b)] = path
            out[(b, v)] = path[::-1] if path else None
        return out

    def truth(self, ctx: "TruthContext", windows: list["AttackWindow"]) -> np.ndarray:
        return ctx.victim_window(windows)
