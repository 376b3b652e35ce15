"""The attack schedule of a run: who attacks whom, and when.

Rules (paper, section 'Attack Implementation', and what its code should have done):
- attackers and victims are UAVs; a composition shares one victim, so a victim of
  `blackhole+dos` carries both labels, and its attacks run over the same interval;
- attackers of different families are different UAVs while the swarm allows it;
- an attack lasts 10-20 s (clipped to the run) and starts at a seeded offset, so attacks do not
  always begin at t = 0;
- each family's own rule (its module in `uavcas.attacks`) picks its attackers: e.g. the
  blackhole credits the victim's first relay, the wormhole takes a UAV off the victim's route.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from uavcas.attacks import ScheduleDraw, family
from uavcas.scenario import Scenario

from .model import Attack

ATTACK_MIN_S = 10.0
ATTACK_MAX_S = 20.0


def schedule_attacks(
    scenario: Scenario,
    uav_names: list[str],
    duration_s: float,
    rng: np.random.Generator,
    routes0: dict[str, list[str]] | None = None,
    detour_windows: Callable[[str, str, float, float], int] | None = None,
) -> list[Attack]:
    """Draw the schedule. `routes0` maps a UAV to its route towards its BS at t = 0 (empty when
    disconnected); `detour_windows(victim, attacker, start_s, stop_s)` counts the windows of an
    attack interval in which a wormhole detour victim -> attacker -> BS exists.

    Shared here: the interval and the victim; each family's module picks its attackers.
    """
    if not scenario.attacks:
        return []
    n = len(uav_names)
    length = float(rng.uniform(ATTACK_MIN_S, ATTACK_MAX_S))
    length = min(length, duration_s)
    start = float(rng.uniform(0.0, duration_s - length)) if duration_s > length else 0.0
    start, stop = round(start, 3), round(min(start + length, duration_s), 3)

    order = [int(i) for i in rng.permutation(n)]
    victim = uav_names[order[0]]
    pool = [uav_names[i] for i in order[1:]]  # candidate attackers, in seeded order
    detours = (lambda v, a: detour_windows(v, a, start, stop)) if detour_windows else None
    draw = ScheduleDraw(uav_names, victim, pool, routes0, rng, detours)
    attacks = []
    for k, spec in enumerate(scenario.attacks):
        fam = family(spec.family)
        attackers = fam.attackers(spec, draw)
        attacks.append(
            Attack(
                attack_id=f"{spec.family}-{k}",
                family=spec.family,
                attackers=attackers,
                victims=[victim],
                start_s=start,
                stop_s=stop,
                params={**fam.params(spec), **fam.drawn_params(spec, draw)},
                spec=spec,
            )
        )
    return attacks
