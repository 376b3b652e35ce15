"""Layer 2 on synthetic flights from the twin's own generators, with known parameters."""

from __future__ import annotations

import numpy as np
import pytest

from uavcas.calibration.layer2_mobility import STEP_S, Track, cruise_slice, fit_mission, score, split_flights
from uavcas.mobility import Area, GaussMarkovParams, GridParams, make_mission


def _tracks(kind, params, n_uav, duration_s, area, seed=7):
    m = make_mission(kind, n_uav, seed=seed, area=area, params=params)
    t = np.arange(0.0, duration_s, STEP_S)
    pos = m.positions(t)
    return [Track(name=f"u{i}", team=0, t_s=t, pos_m=pos[:, i, :]) for i in range(n_uav)]


def test_gauss_markov_fit_recovers_parameters():
    area = Area(x_max_m=20000, y_max_m=20000, z_min_m=0, z_max_m=2000)  # walls far away
    true = GaussMarkovParams(alpha=0.8, mean_speed_mps=3.0, sigma2_mps2=2.0, step_s=1.0, sim_step_s=1.0,
                             mean_vz_mps=0.0, sigma2_z_mps2=0.1)
    tracks = _tracks("random", true, 4, 1500.0, area)
    fit = fit_mission("random", tracks, area, seed=0)
    assert fit.alpha == pytest.approx(0.8, abs=0.04)
    assert fit.mean_speed_mps == pytest.approx(3.0, rel=0.08)
    assert fit.sigma2_mps2 == pytest.approx(2.0, rel=0.15)
    assert fit.sigma2_z_mps2 == pytest.approx(0.1, rel=0.15)
    assert fit.step_s == STEP_S


def test_grid_fit_recovers_speed_and_scores_low_on_itself():
    area = Area(x_max_m=1000, y_max_m=1000, z_min_m=10, z_max_m=60)
    true = GridParams(speed_mps=4.0, altitude_m=30.0, box_width_m=200, box_height_m=150, lane_spacing_m=30.0)
    tracks = _tracks("grid", true, 2, 600.0, area)
    fit = fit_mission("grid", tracks, area, seed=0)
    assert fit.speed_mps == pytest.approx(4.0, abs=0.25)
    assert fit.altitude_m == pytest.approx(30.0)
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
