"""UAV mobility: rectangular spiral, grid (boustrophedon), hover-transit - flown leg by leg
(`legs`: per-leg speeds, acceleration, altitude) - Gauss–Markov 3-D, trace replay.

One protocol (`Mission.positions(t_s)`), bounded to an `Area`, seeded per UAV; the same
generators and parameter models are used by calibration to fit (see `fit.py`, `kinematics.py`).
"""

from uavcas.mobility.area import Area
from uavcas.mobility.base import Mission, MissionBase
from uavcas.mobility.factory import make_mission, mission_seed
from uavcas.mobility.fit import (
    GaussMarkovFit,
    Legs,
    fit_gauss_markov,
    resample_uniform,
    split_legs,
    velocities_from_positions,
)
from uavcas.mobility.gauss_markov import (
    GaussMarkovMission,
    alpha_at_step,
    horizontal_mean_velocity,
    rician_mean_mps,
)
from uavcas.mobility.grid import GridMission, boustrophedon
from uavcas.mobility.hover_transit import HoverTransitMission
from uavcas.mobility.kinematics import Kinematics, kinematics
from uavcas.mobility.params import (
    MISSION_KINDS,
    GaussMarkovParams,
    GridParams,
    HoverTransitParams,
    MissionParams,
    MobilityProfile,
    SpiralParams,
)
from uavcas.mobility.spiral import SpiralMission
from uavcas.mobility.trace import TraceMission

__all__ = [
    "Area",
    "Mission",
    "MissionBase",
    "make_mission",
    "mission_seed",
    "GaussMarkovFit",
    "Legs",
    "split_legs",
    "fit_gauss_markov",
    "resample_uniform",
    "velocities_from_positions",
    "GaussMarkovMission",
    "alpha_at_step",
    "horizontal_mean_velocity",
    "rician_mean_mps",
    "GridMission",
    "boustrophedon",
    "HoverTransitMission",
    "Kinematics",
    "kinematics",
    "MISSION_KINDS",
    "GaussMarkovParams",
    "GridParams",
    "HoverTransitParams",
    "MissionParams",
    "MobilityProfile",
    "SpiralParams",
    "SpiralMission",
    "TraceMission",
]
