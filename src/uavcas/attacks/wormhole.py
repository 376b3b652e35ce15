"""Wormhole: the victim's traffic with its BS is tunnelled through the attacker's switch.

- token `wormhole` (no parameters);
- schedule: the attacker is drawn among UAVs off the victim's route at t = 0, the one with a
  detour (a usable link to the victim, and a usable path to the victim's BS not through it) in
  most windows of the attack, so the detour really adds a hop and really carries traffic;
- plan: in each window the attack overlaps, the planner adds the detour's links where it has one
  (`detours_traffic`, `topology.routing.with_wormholes`: usable links only; a window without
  one gets no override) and lists it, with its hops, in `Window.wormholes`;
- executor: at start the current window is re-applied with the detour: both directions of the
  victim <-> BS traffic (the victim's MAC as source or destination) take the detour's hops
  through the attacker's switch, and nothing else does (alias destination MACs, see
  `network.forwarding`); at stop it is re-applied without. The detour's links are the plan's,
  shaped like any other;
- truth (effect `wormhole`, label source "wormhole-detour"): a packet to or from a victim seen at
  the attacker's switch inside [start, stop), in a window where the plan has the detour: it was
  carried over the attacker's detour. Its other observations carry the same effect;
- provoked: nothing (the default hook). A detoured packet still arrives, and its answer is the
  ordinary conversation, detoured itself when it crosses the attacker's switch."""

from __future__ import annotations

from typing import TYPE_CHECKING, Any, Literal

import numpy as np

from uavcas.network.forwarding import Detour
from uavcas.scenario_model import SpecBase

from .base import AttackExecutor, AttackFamily, ScheduleDraw, TruthContext
from .registry import register

if TYPE_CHECKING:  # types only: the twin's and labels' package __init__s load this registry
    from uavcas.labels.attacklog import AttackWindow
    from uavcas.twin.model import Attack, Window


class WormholeSpec(SpecBase):
    family: Literal["wormhole"] = "wormhole"


@register
class Wormhole(AttackFamily):
    name = "wormhole"
    spec = WormholeSpec
    usage = "wormhole"
    truth_rule = ("a packet to or from the victim seen at the attacker's switch inside [start, stop) in a "
                  "window with the planned detour (carried over the detour)")
    provoked_rule = "nothing (a detoured packet is delivered; its answer is judged by the detour rule)"
    detours_traffic = True

    def attackers(self, spec: SpecBase, draw: ScheduleDraw) -> list[str]:
        on_path = set(draw.routes_start.get(draw.victim, ()))
        off = [u for u in draw.pool if u not in draw.used and u not in on_path]
        # the one with a detour in most of the attack's windows (the first in seeded order on ties)
        attackers = [max(off, key=lambda u: draw.detours(draw.victim, u))] if off else draw.take(1)
        draw.used.update(attackers)
        return attackers

    def start(self, ex: "AttackExecutor", attack: "Attack") -> dict[str, Any]:
        ex.active[attack.attack_id] = attack  # the overrides must see it before the FDB is rebuilt
        return ex.reapply_window()

    def stop(self, ex: "AttackExecutor", attack: "Attack") -> dict[str, Any]:
        del ex.active[attack.attack_id]
        return ex.reapply_window()

    def overrides(self, ex: "AttackExecutor", attack: "Attack", window: "Window") -> list["Detour"]:
        return [Detour(o.victim, o.attacker, o.bs, tuple(o.hops)) for o in window.wormholes
                if o.victim in attack.victims and o.attacker in attack.attackers]

    def effects(self, ctx: "TruthContext", windows: list["AttackWindow"]) -> np.ndarray:
        hit = np.zeros(ctx.n, dtype=bool)
        for w in windows:
            victims, attackers = ctx.node_names(w.victim_ips), ctx.node_names(w.attacker_ips)
            planned = [pw.index for pw in ctx.plan.windows
                       if any(o.victim in victims and o.attacker in attackers for o in pw.wormholes)]
            hit |= (ctx.at_switch_of(attackers) & ctx.during(w.start_unix, w.stop_unix)
                    & ctx.touching(w.victim_ips) & np.isin(ctx.window, planned))
        return ctx.spread(hit)
