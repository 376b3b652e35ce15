"""The attack schedule of a run: who attacks whom, and when.

Rules (paper, section 'Attack Implementation', and what its code should have done):
- attackers and victims are UAVs; a composition shares one victim, so a victim of
  `blackhole+dos` carries both labels, and its attacks run over the same interval;
- DoS, replay and wormhole have one attacker, DDoS two or more (up to a third of the swarm, at
  most 4); attackers of different families are different UAVs while the swarm allows it;
- an attack lasts 10-20 s (clipped to the run) and starts at a seeded offset, so attacks do not
  always begin at t = 0;
- blackhole: the drop rule runs on the victim's switch (as in the paper); its 'attacker' is the
  compromised relay credited with it, the victim's first hop towards its BS when that is a UAV;
- wormhole: the attacker is drawn among UAVs off the victim's route at t = 0 where possible, so
  the detour really adds a hop instead of re-labelling a path the traffic took anyway.
"""

from __future__ import annotations

import numpy as np

from uavcas.scenario import Scenario

from .model import Attack

ATTACK_MIN_S = 10.0
ATTACK_MAX_S = 20.0


def _params(spec) -> dict[str, float | int | str]:
    data = spec.model_dump(exclude={"family"})
    if spec.family in ("dos", "ddos"):
        data["nominal_pps"] = spec.nominal_pps
    return data


def schedule_attacks(
    scenario: Scenario,
    uav_names: list[str],
    duration_s: float,
    rng: np.random.Generator,
    routes0: dict[str, list[str]] | None = None,
) -> list[Attack]:
    """Draw the schedule. `routes0` maps a UAV to its route towards its BS at t = 0."""
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

    def take(k: int) -> list[str]:
        # Prefer UAVs no other family of this composition uses; reuse only when the swarm is small.
        fresh = [u for u in pool if u not in used]
        chosen = (fresh + [u for u in pool if u in used])[:k]
        used.update(chosen)
        return sorted(chosen, key=uav_names.index)

    used: set[str] = set()
    attacks = []
    for k, spec in enumerate(scenario.attacks):
        if spec.family == "ddos":
            hi = max(2, min(4, (n - 1) // 3))
            attackers = take(int(rng.integers(2, hi + 1)))
        elif spec.family == "wormhole":
            on_path = set((routes0 or {}).get(victim, ()))
            off = [u for u in pool if u not in used and u not in on_path]
            attackers = [off[0]] if off else take(1)
            used.update(attackers)
        elif spec.family == "blackhole":
            route = (routes0 or {}).get(victim, [])
            relay = route[1] if len(route) > 1 else None
            if relay in pool and relay not in used:
                used.add(relay)
                attackers = [relay]
            else:
                attackers = take(1)
        else:
            attackers = take(1)
        attacks.append(
            Attack(
                attack_id=f"{spec.family}-{k}",
                family=spec.family,
                attackers=attackers,
                victims=[victim],
                start_s=start,
                stop_s=stop,
                params=_params(spec),
            )
        )
    return attacks
