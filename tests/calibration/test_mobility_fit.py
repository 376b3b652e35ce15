"""Layer 2 on synthetic flights from the twin's own generators, with known parameters."""

from __future__ import annotations

import numpy as np
import pytest

from uavcas.calibration.layer2_mobility import (
    STEP_S,
    Track,
    cruise_slice,
    fit_mission,
    leg_statistics,
    score,
    split_flights,
)
from uavcas.mobility import Area, GaussMarkovParams, GridParams, make_mission


def _tracks(kind, params, n_uav, duration_s, area, seed=7):
    m = make_mission(kind, n_uav, seed=seed, area=area, params=params)
    t = np.arange(0.0, duration_s, STEP_S)
    pos = m.positions(t)
    return [Track(name=f"u{i}", team=0, t_s=t, pos_m=pos[:, i, :]) for i in range(n_uav)]


@pytest.mark.slow  # 16 s on 2 cores
def test_gauss_markov_fit_reproduces_the_speed_law():
    area = Area(x_max_m=20000, y_max_m=20000, z_min_m=0, z_max_m=2000)  # walls far away
    true = GaussMarkovParams(alpha=0.8, mean_speed_mps=3.0, sigma2_mps2=2.0, step_s=1.0, sim_step_s=1.0,
                             mean_vz_mps=0.0, sigma2_z_mps2=0.1)
    tracks = _tracks("random", true, 6, 1500.0, area)
    fit = fit_mission("random", tracks, area, seed=0)
    # Vertical terms from the AR(1) estimator; the speed limit from the flown speeds.
    assert fit.sigma2_z_mps2 == pytest.approx(0.1, rel=0.15) and fit.step_s == STEP_S
    speeds = np.concatenate([t.speeds() for t in tracks])
    assert fit.max_speed_mps == pytest.approx(np.percentile(speeds, 99))
    # alpha, mean speed and variance by JS divergence (the paper's fit): the speed law comes back.
    assert fit.mean_speed_mps == pytest.approx(3.0, rel=0.25)
    held_out = _tracks("random", true, 1, 1500.0, area, seed=99)[0]
    assert score("random", fit, held_out, area, seed=1)["jsd_speed"] < 0.05


def test_grid_fit_recovers_leg_speeds_and_scores_low_on_itself():
    area = Area(x_max_m=1000, y_max_m=1000, z_min_m=10, z_max_m=60)
    true = GridParams(speed_mps=4.0, speed_cv=0.2, accel_mps2=1.0, altitude_m=30.0, altitude_sd_m=1.0,
                      box_width_m=300, box_height_m=150, lane_spacing_m=30.0)
    tracks = _tracks("grid", true, 3, 1200.0, area)
    fit = fit_mission("grid", tracks, area, seed=0)
    # Legs of >= 30 m reach their cruise speed: the lognormal mean and spread come back.
    assert fit.speed_mps == pytest.approx(4.0, rel=0.15) and fit.speed_cv == pytest.approx(0.2, abs=0.1)
    assert fit.accel_mps2 == pytest.approx(1.0, rel=0.5)
    assert fit.altitude_m == pytest.approx(30.0, abs=0.5) and fit.altitude_sd_m == pytest.approx(1.0, abs=0.5)
    s = score("grid", fit, tracks[0], area, seed=1)
    assert 0.0 <= s["jsd_speed"] < 0.2
    assert 0.0 <= s["kl_spatial_bits"] <= np.log2(100) + 1e-9


def test_split_flights_seeded_and_holds_out_30_percent():
    tr, te = split_flights(list("abcde"), seed=0, key=0)
    assert len(te) == 2 and sorted(tr + te) == list(range(5))
    assert split_flights(list("abcde"), 0, 0) == (tr, te)
    assert len(split_flights(list("abc"), 0, 1)[1]) == 1


def test_cruise_slice_drops_takeoff_and_landing():
    alt = np.r_[np.linspace(0, 30, 20), np.full(100, 30.0), np.linspace(30, 0, 20)]
    sl = cruise_slice(alt)
    assert alt[sl].min() >= 24.0 and (sl.stop - sl.start) >= 100


def test_split_legs_finds_the_legs_of_a_spiral():
    from uavcas.mobility import SpiralParams

    area = Area(x_max_m=1000, y_max_m=1000, z_min_m=10, z_max_m=60)
    true = SpiralParams(speed_mps=6.0, speed_cv=0.3, accel_mps2=0.5, altitude_m=25.0, width_m=300, height_m=200,
                        ring_spacing_m=50)
    tracks = _tracks("spiral", true, 2, 1500.0, area)
    stats = leg_statistics(tracks)
    assert stats["n_legs"] > 20 and stats["speed_mps"] == pytest.approx(6.0, rel=0.2)
    assert stats["speed_cv"] == pytest.approx(0.3, abs=0.12)
