"""The attack schedule of a run: who attacks whom, and when.

Rules (paper, section 'Attack Implementation', and what its code should have done):
- attackers and victims are UAVs; a composition shares one victim, so a victim of
  `blackhole+dos` carries both labels, and its attacks run over the same interval;
- attackers of different families are different UAVs while the swarm allows it;
- an attack lasts 10-20 s (clipped to the run) and starts at a seeded offset, so attacks do not
  always begin at t = 0;
- a run may hold several attack *rounds* (`rounds`, default 1 as in the paper): the
  composition again, later in the run, on a victim not attacked before and attackers drawn
  afresh. Rounds never overlap and are at least `ROUND_GAP_S` apart, so one round's
  aftermath (a flood victim's SYN-ACK retransmissions, a replayed exchange's answers) is over
  before the next begins. Why:
  a collaborative class lives on the victim host in the windows where both attacks meet, about
  four windows per round; one round per run leaves the medium preset's classes at ~16
  window-host rows over its four runs, where the benchmark needs 30;
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
ROUND_GAP_S = 5.0


class RoundError(ValueError):
    """Attack rounds that do not fit the run; one-line message."""


def round_intervals(duration_s: float, rounds: int, rng: np.random.Generator) -> list[tuple[float, float]]:
    """[start_s, stop_s) of each round, in time order. One round draws exactly as the schedule
    always did (length, then start), so plans of one round are unchanged."""
    if rounds == 1:
        length = min(float(rng.uniform(ATTACK_MIN_S, ATTACK_MAX_S)), duration_s)
        start = float(rng.uniform(0.0, duration_s - length)) if duration_s > length else 0.0
        return [(round(start, 3), round(min(start + length, duration_s), 3))]
    if rounds < 1:
        raise RoundError(f"rounds must be >= 1, got {rounds}")
    # every round keeps the 10 s minimum; the 20 s maximum is lowered (for all) so that they fit
    cap = min(ATTACK_MAX_S, (duration_s - (rounds - 1) * ROUND_GAP_S) / rounds)
    if cap < ATTACK_MIN_S:
        raise RoundError(f"{rounds} attack rounds of >= {ATTACK_MIN_S:g} s, {ROUND_GAP_S:g} s apart, "
                         f"do not fit a run of {duration_s:g} s")
    lengths = rng.uniform(ATTACK_MIN_S, cap, size=rounds)
    slack = duration_s - float(lengths.sum()) - (rounds - 1) * ROUND_GAP_S
    # the slack goes to the rounds' offsets: sorted uniform cut points, so any layout is possible
    offsets = np.sort(rng.uniform(0.0, slack, size=rounds))
    out, t = [], 0.0
    for k in range(rounds):
        start = t + float(offsets[k]) - (float(offsets[k - 1]) if k else 0.0)
        stop = start + float(lengths[k])
        out.append((round(start, 3), round(min(stop, duration_s), 3)))
        t = stop + ROUND_GAP_S
    return out


def schedule_attacks(
    scenario: Scenario,
    uav_names: list[str],
    duration_s: float,
    rng: np.random.Generator,
    routes_at: Callable[[float], dict[str, list[str]]] | None = None,
    detour_windows: Callable[[str, str, float, float], int] | None = None,
    rounds: int = 1,
) -> list[Attack]:
    """Draw the schedule. `routes_at(t_s)` maps a UAV to its route towards its BS in the window of
    t_s (empty when disconnected), read at each round's start (the blackhole's relay and the
    wormhole's off-path UAV are those of the routes when the attack begins);
    `detour_windows(victim, attacker, start_s, stop_s)` counts the windows of an attack interval
    in which a wormhole detour victim -> attacker -> BS exists.

    Shared here: the intervals and the victims; each family's module picks its attackers.
    """
    if not scenario.attacks:
        return []
    n, n_specs = len(uav_names), len(scenario.attacks)
    if rounds > n:
        raise RoundError(f"{rounds} attack rounds need {rounds} distinct victims; the swarm has {n} UAVs")
    attacks: list[Attack] = []
    for e, (start, stop) in enumerate(round_intervals(duration_s, rounds, rng)):
        order = [int(i) for i in rng.permutation(n)]
        # each round a victim not attacked before: an attacker never repeats a flood on the same
        # victim (its prepared floods would share one nft match), and the victims are more hosts
        victim = next(uav_names[i] for i in order if all(uav_names[i] not in a.victims for a in attacks))
        pool = [u for u in (uav_names[i] for i in order) if u != victim]  # candidate attackers, in seeded order
        detours = (lambda v, a, _s=start, _t=stop: detour_windows(v, a, _s, _t)) if detour_windows else None
        draw = ScheduleDraw(uav_names, victim, pool, routes_at(start) if routes_at else None, rng, detours)
        for k, spec in enumerate(scenario.attacks):
            fam = family(spec.family)
            attackers = fam.attackers(spec, draw)
            attacks.append(
                Attack(
                    attack_id=f"{spec.family}-{e * n_specs + k}",
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
