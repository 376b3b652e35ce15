"""`make_mission`: the scenario's mission name + seed -> a ready mission object.

Each kind draws from its own stream, `uavcas.seeding` stream `kind` of the seed
(SeedSequence([seed, crc32(kind)])), so changing the mission of a scenario does not reuse another
mission's random numbers, and the result is identical across processes and machines.
"""

from __future__ import annotations

from typing import Any, Mapping

import numpy as np

from uavcas import seeding
from uavcas.mobility.area import Area
from uavcas.mobility.base import MissionBase
from uavcas.mobility.gauss_markov import GaussMarkovMission
from uavcas.mobility.grid import GridMission
from uavcas.mobility.hover_transit import HoverTransitMission
from uavcas.mobility.params import MISSION_KINDS, PARAMS_BY_KIND, MissionParams, MobilityProfile
from uavcas.mobility.spiral import SpiralMission

_CLASSES = {
    "spiral": SpiralMission,
    "grid": GridMission,
    "hover_transit": HoverTransitMission,
    "random": GaussMarkovMission,
}


def mission_seed(kind: str, seed: int) -> np.random.SeedSequence:
    return seeding.seed_sequence(seed, kind)


def make_mission(
    kind: str,
    n_uav: int,
    seed: int,
    area: Area = Area(),
    params: MissionParams | MobilityProfile | Mapping[str, Any] | None = None,
) -> MissionBase:
    """Build the mission `kind` (spiral | grid | hover_transit | random) for n_uav UAVs.

    `params`: None (paper defaults), the kind's params model, a `MobilityProfile` (its entry for
    `kind` is used), or a dict validated into the kind's params model.
    """
    if kind not in _CLASSES:
        raise ValueError(f"unknown mission {kind!r}; expected one of {', '.join(MISSION_KINDS)}")
    model = PARAMS_BY_KIND[kind]
    if params is None:
        p = model()
    elif isinstance(params, MobilityProfile):
        p = params.for_kind(kind)
    elif isinstance(params, Mapping):
        p = model.model_validate({"kind": kind, **params})
    elif isinstance(params, model):
        p = params
    else:
        raise TypeError(f"params for {kind!r} must be {model.__name__}, a MobilityProfile or a dict; got "
                        f"{type(params).__name__}")
    return _CLASSES[kind](n_uav, p, area, mission_seed(kind, seed))
