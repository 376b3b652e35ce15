"""Mission parameters as JSON-serialisable pydantic models, and the `MobilityProfile`.

Defaults are the paper's table `tab:mobility_params` (fitted on AFAR/AADM flights); the
geometric parameters the table does not give (spiral footprint/rings, grid box/lanes, hover
time, Gauss–Markov reference step and vertical mean) are our documented choices, and the
paper's constant speeds are kept as constant (speed_cv 0, no acceleration limit), which calibration
(layer 2) may overwrite by writing a profile. Fitted altitudes are kept as fitted; the clamp to
the area's altitude band happens when a mission is built (see `Area.clamp_altitude`), so a
profile records what the data said and the twin records what it flew.
"""

from __future__ import annotations

from typing import Literal, Optional

from pydantic import BaseModel, ConfigDict, Field, model_validator

from uavcas.vocabulary import MISSIONS as MISSION_KINDS  # the one list of missions


class _Params(BaseModel):
    model_config = ConfigDict(frozen=True, extra="forbid")

    # Anchors keep this distance from the area faces so a mission's footprint starts inside it.
    margin_m: float = Field(10.0, ge=0)
    # Dart-throwing target for the distance between two UAVs' anchors (relaxed if infeasible).
    min_separation_m: float = Field(25.0, ge=0)


class _LegParams(_Params):
    """Leg-by-leg flight (`uavcas.mobility.legs`): per-leg cruise speeds drawn around
    `speed_mps` with coefficient of variation `speed_cv`, acceleration limit `accel_mps2`
    (None: instant speed changes, i.e. constant speed on every leg), per-leg altitude spread
    `altitude_sd_m` around `altitude_m`."""

    speed_mps: float = Field(5.0, ge=0)
    speed_cv: float = Field(0.0, ge=0)
    accel_mps2: Optional[float] = Field(None, gt=0)
    altitude_m: float = 30.0
    altitude_sd_m: float = Field(0.0, ge=0)


class SpiralParams(_LegParams):
    """Rectangular spiral at fixed altitude: expanding axis-aligned legs from the centre out to a
    `width_m` x `height_m` footprint, then back in (the AFAR "spiral" search pattern: 74-92 %
    of its moving steps are axis-aligned). Leg lengths grow by one ring unit every two legs
    (unit = width / 2R along x, height / 2R along y, R = rings of `ring_spacing_m`)."""

    kind: Literal["spiral"] = "spiral"
    width_m: float = Field(300.0, gt=0)  # AFAR spiral footprint (about 300 x 215 m)
    height_m: float = Field(215.0, gt=0)
    ring_spacing_m: float = Field(40.0, gt=0)
    speed_mps: float = Field(0.570, ge=0)  # paper table
    altitude_m: float = 25.96  # paper table (fitted); clamped to the band -> 30 m


class GridParams(_LegParams):
    """Boustrophedon (lawn-mower) sweep of a bounding box at fixed altitude, leg by leg.

    `box_m` = (x0, y0, x1, y1) fixes one box shared by all UAVs (spread along the sweep by phase);
    when None each UAV sweeps its own box of `box_width_m` x `box_height_m` around its anchor.
    """

    kind: Literal["grid"] = "grid"
    box_m: Optional[tuple[float, float, float, float]] = None
    box_width_m: float = Field(200.0, gt=0)
    box_height_m: float = Field(200.0, gt=0)
    lane_spacing_m: float = Field(50.0, gt=0)
    speed_mps: float = Field(9.960, ge=0)  # paper table
    altitude_m: float = 26.06  # paper table (fitted); clamped to the band -> 30 m

    @model_validator(mode="after")
    def _check_box(self) -> "GridParams":
        if self.box_m is not None:
            x0, y0, x1, y1 = self.box_m
            if not (x1 > x0 and y1 > y0):
                raise ValueError(f"grid box_m={self.box_m} must have x1 > x0 and y1 > y0")
        return self


class HoverTransitParams(_LegParams):
    """Closed tour of waypoints: hover `hover_s` at each, fly straight legs in between.

    Waypoints are seeded within `leg_radius_m` of the UAV's anchor, or all UAVs share
    `waypoints_m` (x, y) when given. The paper fitted 37.53 m and forces 50 m to keep hovering
    UAVs inside the operational envelope; we keep 50 m as the default.
    """

    kind: Literal["hover_transit"] = "hover_transit"
    speed_mps: float = Field(9.962, gt=0)  # paper table
    altitude_m: float = 50.0  # paper: forced to 50 m (fitted 37.53 m)
    hover_s: float = Field(10.0, ge=0)
    n_waypoints: int = Field(4, ge=2)
    leg_radius_m: float = Field(120.0, gt=0)
    waypoints_m: Optional[list[tuple[float, float]]] = None

    @model_validator(mode="after")
    def _check_waypoints(self) -> "HoverTransitParams":
        if self.waypoints_m is not None and len(self.waypoints_m) < 2:
            raise ValueError("hover_transit waypoints_m needs at least 2 waypoints")
        return self


class GaussMarkovParams(_Params):
    """3-D Gauss–Markov walk (Liang & Haas 1999; Camp et al. 2002), per axis at step dt0:

        v_k = a v_{k-1} + (1 - a) vbar + sqrt(1 - a^2) sigma w_k,   w_k ~ N(0, 1)

    `alpha` and `sigma2_mps2` are defined at the reference step `step_s` (dt0). Any other
    simulation step dt uses the exact Ornstein–Uhlenbeck discretisation
        a_dt = alpha ** (dt / dt0)            (same correlation time tau = -dt0 / ln alpha)
        sigma unchanged                        (same stationary variance sigma^2)
    so velocity statistics (variance, autocorrelation at a given lag in seconds, speed
    distribution) do not depend on the simulation step.

    `mean_speed_mps` is the long-run mean *horizontal* speed E|v_xy|. With per-axis Gaussian
    velocities the horizontal speed is Rician(nu, sigma), so the horizontal mean-velocity
    magnitude nu is solved from the Rician mean; each UAV gets a seeded mean heading. If the
    requested mean speed is below sigma*sqrt(pi/2) (the Rayleigh mean, nu = 0) the horizontal
    sigma is lowered to mean_speed/sqrt(pi/2) so that the mean speed is still honoured.
    """

    kind: Literal["random"] = "random"
    alpha: float = Field(0.629, ge=0, lt=1)  # paper table, per step_s
    mean_speed_mps: float = Field(2.501, ge=0)  # paper table, long-run mean horizontal speed
    sigma2_mps2: float = Field(3.713, ge=0)  # paper table, per-axis stationary variance
    # Reference step at which alpha was fitted. The paper does not state it; we take 1 s, the
    # step our layer-2 calibration resamples flights to (it writes its own step_s with alpha).
    step_s: float = Field(1.0, gt=0)
    # Paper: "a negative vertical mean (tendency to descend)", value not given. AFAR flights
    # show |mean v_z| ~ 0.01 m/s; -0.05 m/s is our placeholder until calibration writes one.
    mean_vz_mps: float = -0.05
    # None -> the paper's isotropic form (same sigma^2 on z); a fitter may set z separately.
    sigma2_z_mps2: Optional[float] = Field(None, ge=0)
    # Internal simulation step; positions are linearly interpolated in between.
    sim_step_s: float = Field(0.5, gt=0)
    # Speed limit of the autopilot: the UAV flies the state velocity scaled down to this
    # horizontal speed when it is faster (the state itself evolves unsaturated). None: no limit
    # (the paper's walk). The AFAR "random" flights cruise against a ~5 m/s limit.
    max_speed_mps: Optional[float] = Field(None, gt=0)


MissionParams = SpiralParams | GridParams | HoverTransitParams | GaussMarkovParams

PARAMS_BY_KIND: dict[str, type[_Params]] = {
    c.model_fields["kind"].default: c for c in (SpiralParams, GridParams, HoverTransitParams, GaussMarkovParams)
}
if set(PARAMS_BY_KIND) != set(MISSION_KINDS):
    raise ImportError(f"mission parameter models {sorted(PARAMS_BY_KIND)} != vocabulary {sorted(MISSION_KINDS)}")


class MobilityProfile(BaseModel):
    """One parameter set per mission; the paper's fit by default. Calibration writes these."""

    model_config = ConfigDict(frozen=True, extra="forbid")

    name: str = "paper"
    source: str = "paper table tab:mobility_params (AFAR/AADM fit) + uavcas geometric defaults"
    spiral: SpiralParams = SpiralParams()
    grid: GridParams = GridParams()
    hover_transit: HoverTransitParams = HoverTransitParams()
    random: GaussMarkovParams = GaussMarkovParams()

    def for_kind(self, kind: str) -> MissionParams:
        if kind not in MISSION_KINDS:
            raise ValueError(f"unknown mission {kind!r}; expected one of {', '.join(MISSION_KINDS)}")
        return getattr(self, kind)

    def to_json(self) -> str:
        return self.model_dump_json(indent=1) + "\n"

    @classmethod
    def from_json(cls, text: str) -> "MobilityProfile":
        return cls.model_validate_json(text)
