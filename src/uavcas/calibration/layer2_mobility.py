"""Layer 2: mission parameters fitted to the AFAR flights with the twin's own generators.

Flights -> tracks: lon/lat to local east/north metres about the rover (the transmitter), altitude
as logged; the mission phase is the longest run of samples at >= 80 % of the flight's median
altitude (take-off and landing are not part of any twin mission, which start airborne); then
`mobility.resample_uniform` to a fixed STEP_S = 1 s (the step `GaussMarkovParams.step_s`
documents) and `mobility.kinematics` (horizontal speed, heading-change rate, vertical speed,
altitude) - the same function is applied to simulated missions.

Mission assignment: the paper's (spiral = teams 301 and 309, grid = 328, hover-transit = 288,
random = 300); another mapping can be passed. Per mission, a seeded 30 % of its flights
(at least one) is held out; parameters are fitted on the rest, always through the generator
the twin flies (`make_mission`):

* spiral / grid / hover-transit (leg by leg, `uavcas.mobility.legs`): the training tracks are
  cut into straight legs (`mobility.split_legs`, Douglas-Peucker at 4 m); the per-leg cruise
  speed distribution is the lognormal with the mean and coefficient of variation of the peak
  speeds of legs >= 30 m (shorter ones never reach cruise); the altitude is the median flown,
  its per-leg spread the std of the legs' median altitudes. Geometry: spiral and grid
  footprints = median 5-95 % extent of the tracks, hover-transit leg radius = median 95th
  percentile distance from the centroid. Then by grid search with the generator: the
  acceleration limit (and hover-transit's hover time) minimise the speed JS divergence against
  the pooled training speeds; the spiral's ring spacing and the grid's lane spacing minimise
  the JS divergence of |heading-change rate|.
* random: `mobility.fit_gauss_markov` (the AR(1) estimator of the generator) on the training
  velocities gives the vertical terms; the speed limit is the 99th percentile of the training
  speeds (the AFAR "random" flights cruise against a ~5 m/s autopilot limit); alpha, the mean
  speed and the variance are then chosen by grid search against the training speed
  distribution, as the paper fits Gauss-Markov ("by minimizing JSD against velocity
  distributions"), simulating RANDOM_SIM_UAV UAVs per candidate (the walk's memory makes a
  few UAVs a noisy sample).

Held-out evaluation: each held-out flight against N_SIM_UAV simulated UAVs flying as long as
it: speed JS *divergence* (base 2, in [0, 1], bins 0.25 m/s shared by both samples) and JS
*distance* (its square root, scipy's `jensenshannon`; the paper's table reports this one),
|heading-rate| JS divergence, and spatial KL(real || sim) in bits on 10 m cells of the tracks
centred on their centroids (placement in the field is arbitrary), smoothed as the 0.01-skew
divergence (metrics.py; bounded by 6.64 bits). The paper-default parameters are scored the
same way as a baseline.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from uavcas import seeding
from uavcas.mobility import (
    Area,
    GridParams,
    HoverTransitParams,
    MobilityProfile,
    SpiralParams,
    fit_gauss_markov,
    kinematics,
    make_mission,
    resample_uniform,
    split_legs,
    velocities_from_positions,
)
from uavcas.vocabulary import MISSIONS

from .loaders import AfarFlight, CalibrationDataError, local_xy_m
from .metrics import jsd_on_shared_bins, spatial_kl_bits

STEP_S = 1.0
SPEED_BIN_MPS = 0.25
HEADING_BIN_RADPS = 0.05
CELL_M = 10.0
N_SIM_UAV = 4
RANDOM_SIM_UAV = 16
CRUISE_FRACTION = 0.8
PAPER_ASSIGNMENT = {301: "spiral", 309: "spiral", 328: "grid", 288: "hover_transit", 300: "random"}


@dataclass(frozen=True)
class Track:
    """A flight on a uniform time grid, positions in metres relative to the rover."""

    name: str
    team: int
    t_s: np.ndarray
    pos_m: np.ndarray  # (T, 3)

    @property
    def duration_s(self) -> float:
        return float(self.t_s[-1] - self.t_s[0])

    def speeds(self) -> np.ndarray:
        return kinematics(self.pos_m, self.t_s).horizontal_speed_mps

    def heading_rates(self) -> np.ndarray:
        return np.abs(kinematics(self.pos_m, self.t_s).heading_rate_radps)

    def centred_xy(self) -> np.ndarray:
        return self.pos_m[:, :2] - self.pos_m[:, :2].mean(axis=0)


def flight_xyz_m(f: AfarFlight) -> np.ndarray:
    """(T, 3) east/north/up metres about the rover (or the flight's mean if it has none)."""
    lon0, lat0 = f.rover_lon_lat if f.rover_lon_lat is not None else (float(np.mean(f.lon_deg)),
                                                                      float(np.mean(f.lat_deg)))
    x, y = local_xy_m(f.lon_deg, f.lat_deg, lon0, lat0)
    return np.c_[x, y, f.alt_m]


def cruise_slice(alt_m: np.ndarray) -> slice:
    """Longest run of samples at >= CRUISE_FRACTION x median altitude."""
    ok = alt_m >= CRUISE_FRACTION * np.median(alt_m)
    edges = np.flatnonzero(np.diff(np.r_[0, ok.astype(int), 0]))
    starts, stops = edges[::2], edges[1::2]
    k = int(np.argmax(stops - starts))
    return slice(int(starts[k]), int(stops[k]))


def to_track(f: AfarFlight, step_s: float = STEP_S) -> Track:
    xyz = flight_xyz_m(f)
    sl = cruise_slice(xyz[:, 2])
    t, pos = resample_uniform(f.t_s[sl], xyz[sl], step_s)
    return Track(name=f.name, team=f.team, t_s=t - t[0], pos_m=pos)


def sim_track(kind: str, params, duration_s: float, seed: int, area: Area, n_uav: int = N_SIM_UAV) -> list[Track]:
    """`n_uav` UAVs of the twin's mission, sampled every STEP_S like the real tracks."""
    m = make_mission(kind, n_uav, seed=seed, area=area, params=params)
    t = np.arange(0.0, max(duration_s, 10 * STEP_S) + 1e-9, STEP_S)
    pos = m.positions(t)
    return [Track(name=f"sim{i}", team=-1, t_s=t, pos_m=pos[:, i, :]) for i in range(n_uav)]


def _speeds(tracks: list[Track]) -> np.ndarray:
    return np.concatenate([t.speeds() for t in tracks])


def _heading(tracks: list[Track]) -> np.ndarray:
    return np.concatenate([t.heading_rates() for t in tracks])


def sim_area(tracks: list[Track]) -> Area:
    """A field big enough for the flights' footprints; altitude band covering the flights."""
    z = np.concatenate([t.pos_m[:, 2] for t in tracks])
    ext = max(float(np.ptp(np.concatenate([t.pos_m[:, :2] for t in tracks]), axis=0).max()), 100.0)
    side = 3.0 * ext
    return Area(x_max_m=side, y_max_m=side, z_min_m=max(float(z.min()) - 1.0, 0.0), z_max_m=float(z.max()) + 1.0)


def _argmin(values, score) -> float:
    scores = [score(v) for v in values]
    return values[int(np.argmin(scores))]


LEG_TOL_M = 4.0
CRUISE_LEG_M = 30.0
ACCEL_GRID = (0.25, 0.5, 0.75, 1.0, 1.5, 2.0, 3.0, 5.0)


def leg_statistics(train: list[Track]) -> dict:
    """Per-leg cruise speed mean / cv, altitude and its per-leg spread of the training tracks."""
    legs = [split_legs(t.pos_m, t.t_s, LEG_TOL_M) for t in train]
    length = np.concatenate([lg.length_m for lg in legs])
    peak = np.concatenate([lg.peak_speed_mps for lg in legs])
    alt = np.concatenate([lg.altitude_m for lg in legs])
    cruise = peak[length >= CRUISE_LEG_M] if np.count_nonzero(length >= CRUISE_LEG_M) >= 3 else peak
    mean = float(np.mean(cruise))
    return {"speed_mps": mean, "speed_cv": float(np.std(cruise) / mean) if mean > 0 else 0.0,
            "altitude_m": float(np.median(np.concatenate([t.pos_m[:, 2] for t in train]))),
            "altitude_sd_m": float(np.std(alt)), "n_legs": int(length.size), "n_cruise_legs": int(cruise.size)}


def fit_mission(kind: str, train: list[Track], area: Area, seed: int):
    """Fitted parameters of `kind` on the training tracks (see module docstring)."""
    speeds = _speeds(train)
    heading = _heading(train)
    radius = float(np.median([np.percentile(np.linalg.norm(t.centred_xy(), axis=1), 95) for t in train]))
    ext = np.median([np.ptp(np.percentile(t.pos_m[:, :2], [5, 95], axis=0), axis=0) for t in train], axis=0)
    dur = 600.0

    def speed_jsd(params) -> float:
        return jsd_on_shared_bins(_speeds(sim_track(kind, params, dur, seed, area)), speeds, SPEED_BIN_MPS)[0]

    def heading_jsd(params) -> float:
        return jsd_on_shared_bins(_heading(sim_track(kind, params, dur, seed, area)), heading, HEADING_BIN_RADPS)[0]

    def best(base, field: str, values, score):
        v = _argmin(list(values), lambda x: score(base.model_copy(update={field: x})))
        return base.model_copy(update={field: v})

    if kind == "random":
        vel = [velocities_from_positions(t.pos_m, STEP_S) for t in train]
        gm = fit_gauss_markov(vel, STEP_S).to_params(max_speed_mps=float(np.percentile(speeds, 99)))
        cands = [(a, m, s2) for a in (0.5, 0.65, 0.8, 0.9, 0.95, 0.99) for m in (0.6, 0.8, 1.0, 1.2, 1.4)
                 for s2 in (0.25, 0.5, 1.0, 2.0, 4.0, 8.0)]

        def gm_jsd(c) -> float:
            p = gm.model_copy(update={"alpha": c[0], "mean_speed_mps": c[1] * float(np.mean(speeds)),
                                      "sigma2_mps2": c[2]})
            return jsd_on_shared_bins(_speeds(sim_track(kind, p, dur, seed, area, RANDOM_SIM_UAV)), speeds,
                                      SPEED_BIN_MPS)[0]

        a, m, s2 = _argmin(cands, gm_jsd)
        return gm.model_copy(update={"alpha": float(a), "mean_speed_mps": float(m * np.mean(speeds)),
                                     "sigma2_mps2": float(s2)})
    legs = leg_statistics(train)
    common = {k: legs[k] for k in ("speed_mps", "speed_cv", "altitude_m", "altitude_sd_m")}
    if kind == "spiral":
        base = SpiralParams(**common, width_m=float(max(ext[0], 20.0)), height_m=float(max(ext[1], 20.0)),
                            accel_mps2=1.0)
        base = best(base, "accel_mps2", ACCEL_GRID, speed_jsd)
        return best(base, "ring_spacing_m", (10.0, 15.0, 20.0, 30.0, 40.0, 60.0), heading_jsd)
    if kind == "grid":
        base = GridParams(**common, box_width_m=float(max(ext[0], 20.0)), box_height_m=float(max(ext[1], 20.0)),
                          accel_mps2=1.0)
        base = best(base, "accel_mps2", ACCEL_GRID, speed_jsd)
        return best(base, "lane_spacing_m", (10.0, 20.0, 30.0, 50.0, 80.0), heading_jsd)
    if kind == "hover_transit":
        base = HoverTransitParams(**common, leg_radius_m=max(radius, 20.0), accel_mps2=1.0)
        cands = [(a, h) for a in ACCEL_GRID for h in (0.0, 5.0, 10.0, 20.0, 40.0, 80.0)]
        a, h = _argmin(cands, lambda c: speed_jsd(base.model_copy(update={"accel_mps2": c[0], "hover_s": c[1]})))
        return base.model_copy(update={"accel_mps2": float(a), "hover_s": float(h)})
    raise ValueError(f"unknown mission {kind!r}")


def score(kind: str, params, test: Track, area: Area, seed: int) -> dict:
    sims = sim_track(kind, params, test.duration_s, seed, area, RANDOM_SIM_UAV if kind == "random" else N_SIM_UAV)
    jsd_speed, _ = jsd_on_shared_bins(_speeds(sims), test.speeds(), SPEED_BIN_MPS)
    jsd_dist = float(np.sqrt(jsd_speed))
    jsd_head, _ = jsd_on_shared_bins(_heading(sims), test.heading_rates(), HEADING_BIN_RADPS)
    kl = float(np.mean([spatial_kl_bits(test.centred_xy(), s.centred_xy(), CELL_M) for s in sims]))
    return {"flight": test.name, "jsd_speed": float(jsd_speed), "js_distance_speed": jsd_dist,
            "jsd_heading_rate": float(jsd_head), "kl_spatial_bits": kl,
            "real_mean_speed_mps": float(test.speeds().mean()), "sim_mean_speed_mps": float(_speeds(sims).mean())}


@dataclass
class Layer2Result:
    profile: MobilityProfile
    missions: dict
    tracks: dict  # mission -> {"train": [Track], "test": [Track]}
    area: Area
    assignment: dict


def split_flights(names: list[str], seed: int, key: int, frac: float = 0.3) -> tuple[list[int], list[int]]:
    n = len(names)
    n_test = max(1, int(round(frac * n))) if n > 1 else 0
    perm = seeding.generator(seed, key).permutation(n)
    test = sorted(perm[:n_test].tolist())
    return [i for i in range(n) if i not in test], test


def run_layer2(flights: list[AfarFlight], seed: int = 0, assignment: dict[int, str] | None = None) -> Layer2Result:
    assignment = assignment or PAPER_ASSIGNMENT
    tracks = [to_track(f) for f in flights]
    area = sim_area(tracks)
    fitted: dict = {}
    out: dict = {}
    split: dict = {}
    for key, kind in enumerate(MISSIONS):
        mine = [t for t in tracks if assignment.get(t.team) == kind]
        if not mine:
            continue
        tr_i, te_i = split_flights([t.name for t in mine], seed, key)
        train, test = [mine[i] for i in tr_i], [mine[i] for i in te_i]
        if not train:  # a single flight: fit and score on it, and say so
            train = test
        params = fit_mission(kind, train, area, seed)
        fitted[kind] = params
        default = MobilityProfile().for_kind(kind)
        scores = [score(kind, params, t, area, seed + 1) for t in test]
        base = [score(kind, default, t, area, seed + 1) for t in test]
        split[kind] = {"train": train, "test": test}
        out[kind] = {
            "params": params.model_dump(mode="json"),
            "train_flights": [t.name for t in train],
            "test_flights": [t.name for t in test],
            "heldout": {
                "jsd_speed": float(np.mean([s["jsd_speed"] for s in scores])),
                "js_distance_speed": float(np.mean([s["js_distance_speed"] for s in scores])),
                "jsd_heading_rate": float(np.mean([s["jsd_heading_rate"] for s in scores])),
                "kl_spatial_bits": float(np.mean([s["kl_spatial_bits"] for s in scores])),
                "per_flight": scores,
            },
            "paper_default_heldout": {
                "jsd_speed": float(np.mean([s["jsd_speed"] for s in base])),
                "js_distance_speed": float(np.mean([s["js_distance_speed"] for s in base])),
                "kl_spatial_bits": float(np.mean([s["kl_spatial_bits"] for s in base])),
            },
            "train_legs": leg_statistics(train) if kind != "random" else None,
            "train_kinematics": {
                "mean_speed_mps": float(_speeds(train).mean()),
                "median_altitude_m": float(np.median(np.concatenate([t.pos_m[:, 2] for t in train]))),
                "mean_abs_vertical_speed_mps": float(np.mean([np.abs(kinematics(t.pos_m, t.t_s).vertical_speed_mps)
                                                              .mean() for t in train])),
                "median_abs_heading_rate_radps": float(np.median(_heading(train))),
            },
        }
    if not fitted:
        teams = sorted({t.team for t in tracks})
        raise CalibrationDataError(f"no AFAR flight is assigned to a mission (teams found: {teams}); pass an "
                                   "assignment")
    profile = MobilityProfile(
        name="calibrated", source=f"uavcas calibrate mobility: AFAR flights, step {STEP_S:g} s, seed {seed}",
        **{k: v for k, v in fitted.items()},
    )
    return Layer2Result(profile, out, split, area, {str(k): v for k, v in assignment.items()})


def layer2_json(res: Layer2Result) -> dict:
    return {
        "step_s": STEP_S,
        "assignment": res.assignment,
        "jsd": ("Jensen-Shannon divergence, base 2, in [0, 1]; shared bins of %.2f m/s covering both samples"
                % SPEED_BIN_MPS),
        "js_distance": "Jensen-Shannon distance = sqrt(divergence) (scipy.spatial.distance.jensenshannon, base 2)",
        "kl_spatial": f"KL(real || sim) in bits, {CELL_M:g} m cells on centred tracks, skew-smoothed KL(p || 0.99 q + "
                      "0.01 p), bounded by 6.64 bits (metrics.KL_SKEW)",
        "sim_area": res.area.model_dump(),
        "missions": res.missions,
    }
