"""Gauss–Markov: stationary speed and variance, time-step invariance, reflection, fitting."""

from __future__ import annotations

import numpy as np
import pytest

from uavcas.mobility import (
    Area,
    GaussMarkovMission,
    GaussMarkovParams,
    alpha_at_step,
    fit_gauss_markov,
    horizontal_mean_velocity,
    kinematics,
    make_mission,
    resample_uniform,
    rician_mean_mps,
    velocities_from_positions,
)

# A box so large that no UAV meets a wall in the test horizon: the pure velocity process.
HUGE = Area(x_max_m=1e7, y_max_m=1e7, z_min_m=0.0, z_max_m=1e7)


def _velocity_states(params, n_uav=200, horizon_s=2000.0, sample_s=1.0, area=Area(), seed=11):
    m = GaussMarkovMission(n_uav, params, area, seed)
    t = np.arange(0.0, horizon_s, sample_s)
    return m, t, m.velocities(t)


def test_time_scaling_rule():
    assert alpha_at_step(0.629, 1.0, 1.0) == pytest.approx(0.629)
    assert alpha_at_step(0.629, 1.0, 0.5) == pytest.approx(0.629**0.5)
    assert alpha_at_step(0.629, 1.0, 5.0) == pytest.approx(0.629**5)
    # Two half steps compose to one full step (semigroup property of the OU process).
    assert alpha_at_step(0.629, 1.0, 0.5) ** 2 == pytest.approx(alpha_at_step(0.629, 1.0, 1.0))
    assert alpha_at_step(0.0, 1.0, 0.5) == 0.0


def test_rician_mean_matches_monte_carlo_and_inversion():
    rng = np.random.default_rng(0)
    for nu, sigma in [(0.0, 1.9), (0.73, 1.93), (3.0, 1.0), (10.0, 0.5)]:
        v = rng.normal(size=(400_000, 2)) * sigma + np.array([nu, 0.0])
        assert float(rician_mean_mps(nu, sigma)) == pytest.approx(np.hypot(v[:, 0], v[:, 1]).mean(), rel=5e-3)
    nu, sigma_h = horizontal_mean_velocity(2.501, np.sqrt(3.713))
    assert sigma_h == pytest.approx(np.sqrt(3.713)) and 0.5 < nu < 1.0
    assert float(rician_mean_mps(nu, sigma_h)) == pytest.approx(2.501, rel=1e-9)
    # Infeasible with that sigma (Rayleigh mean 2.415 > 1.0): sigma_h is lowered, nu = 0.
    nu, sigma_h = horizontal_mean_velocity(1.0, np.sqrt(3.713))
    assert nu == 0.0 and float(rician_mean_mps(0.0, sigma_h)) == pytest.approx(1.0)


@pytest.mark.parametrize(
    "params",
    [
        GaussMarkovParams(),  # the paper's fit
        GaussMarkovParams(mean_speed_mps=6.0, sigma2_mps2=1.0, alpha=0.9),
        GaussMarkovParams(mean_speed_mps=1.0),  # below the Rayleigh mean of sigma: sigma lowered
    ],
)
def test_long_run_mean_horizontal_speed_is_the_configured_one(params):
    # In the real 1000 x 1000 x [30, 110] box, walls included, from positions (what the twin uses).
    m = make_mission("random", 100, 5, params=params)
    t = np.arange(0.0, 1500.0, params.sim_step_s)
    k = kinematics(m.positions(t), t)
    assert k.horizontal_speed_mps.mean() == pytest.approx(params.mean_speed_mps, rel=0.03)
    # And from the velocity state itself.
    v = m.velocities(t)
    assert np.hypot(v[..., 0], v[..., 1]).mean() == pytest.approx(params.mean_speed_mps, rel=0.03)


def test_paper_gm_is_not_the_naive_reading():
    # Guard against the defect of using 2.501 as the mean *velocity* magnitude: that would give
    # a long-run mean speed near 3.4 m/s, far from the configured 2.501.
    assert float(rician_mean_mps(2.501, np.sqrt(3.713))) > 3.2


def test_stationary_per_axis_variance_is_sigma2():
    p = GaussMarkovParams()
    _, _, v = _velocity_states(p, area=HUGE)
    # Remove each UAV's own mean (its seeded heading), then pool.
    var = (v - v.mean(axis=0, keepdims=True)).var(axis=(0, 1))
    assert var == pytest.approx([3.713, 3.713, 3.713], rel=0.04)
    assert v[..., 2].mean() == pytest.approx(p.mean_vz_mps, abs=0.03)  # the descent tendency


def test_separate_vertical_sigma():
    p = GaussMarkovParams(sigma2_z_mps2=0.25)
    _, _, v = _velocity_states(p, area=HUGE, n_uav=100)
    assert v[..., 2].var() == pytest.approx(0.25, rel=0.05)


@pytest.mark.parametrize("sim_step_s", [0.1, 0.25, 1.0, 2.0])
def test_statistics_do_not_depend_on_the_simulation_step(sim_step_s):
    p = GaussMarkovParams(sim_step_s=sim_step_s)
    _, _, v = _velocity_states(p, area=HUGE, sample_s=2.0)
    d = v - v.mean(axis=0, keepdims=True)
    var = d.var(axis=(0, 1))
    assert var == pytest.approx([3.713] * 3, rel=0.05)
    # Correlation at a lag of 2 s is alpha^(2 s / step_s), whatever the simulation step.
    lag = (d[1:] * d[:-1]).mean(axis=(0, 1)) / var
    assert lag == pytest.approx([0.629**2] * 3, abs=0.03)
    speed = np.hypot(v[..., 0], v[..., 1]).mean()
    assert speed == pytest.approx(2.501, rel=0.03)


def test_reflection_keeps_speed_and_turns_back():
    area = Area(x_max_m=100, y_max_m=100, z_min_m=30, z_max_m=40)  # walls hit constantly
    p = GaussMarkovParams(mean_speed_mps=5.0)
    m = GaussMarkovMission(50, p, area, 3)
    t = np.arange(0.0, 2000.0, p.sim_step_s)
    pos = m.positions(t)
    assert area.contains(pos, tol_m=1e-9)
    v = m.velocities(t)
    assert np.hypot(v[..., 0], v[..., 1]).mean() == pytest.approx(5.0, rel=0.03)
    # Walls are actually touched: the walk explores the whole box, including both z faces.
    assert pos[..., 2].min() < 30.5 and pos[..., 2].max() > 39.5


def test_descending_mean_pulls_uavs_down_before_the_floor():
    p = GaussMarkovParams(mean_vz_mps=-1.0, sigma2_z_mps2=0.01)
    m = make_mission("random", 20, 0, params=p)
    z = m.positions(np.array([0.0, 5.0]))[..., 2]
    assert np.all(z[1] < z[0])


def test_gm_fit_recovers_known_parameters():
    true = GaussMarkovParams(alpha=0.8, mean_speed_mps=4.0, sigma2_mps2=2.0, sigma2_z_mps2=0.25, mean_vz_mps=-0.1,
                             step_s=1.0, sim_step_s=1.0)
    m = GaussMarkovMission(100, true, HUGE, 21)
    t = np.arange(0.0, 3000.0, 1.0)
    v = velocities_from_positions(m.positions(t), 1.0)  # positions only, as a real log would be
    fit = fit_gauss_markov(v, 1.0)
    assert fit.alpha == pytest.approx(0.8, abs=0.01)
    assert fit.alpha_axes[2] == pytest.approx(0.8, abs=0.01)
    assert fit.sigma2_mps2 == pytest.approx(2.0, rel=0.03)
    assert fit.sigma2_axes_mps2[2] == pytest.approx(0.25, rel=0.03)
    assert fit.mean_horizontal_speed_mps == pytest.approx(4.0, rel=0.02)
    assert fit.mean_velocity_mps[2] == pytest.approx(-0.1, abs=0.01)
    # The fitted parameters drive the same generator back to the same speed law.
    back = fit.to_params(sim_step_s=0.5)
    m2 = make_mission("random", 50, 1, params=back)
    tt = np.arange(0.0, 1000.0, 0.5)
    assert np.hypot(*m2.velocities(tt)[..., :2].transpose(2, 0, 1)).mean() == pytest.approx(4.0, rel=0.03)


def test_gm_fit_at_another_sampling_step_follows_the_scaling_rule():
    # Simulated at 0.25 s, sampled and fitted at 2 s: alpha_2s = alpha^(2/1).
    true = GaussMarkovParams(alpha=0.9, step_s=1.0, sim_step_s=0.25)
    m = GaussMarkovMission(100, true, HUGE, 4)
    t = np.arange(0.0, 4000.0, 2.0)
    fit = fit_gauss_markov(m.velocities(t), 2.0)
    assert fit.alpha == pytest.approx(0.9**2, abs=0.015)
    assert fit.sigma2_mps2 == pytest.approx(3.713, rel=0.04)


def test_fit_accepts_irregular_logs_after_resampling():
    rng = np.random.default_rng(0)
    t = np.cumsum(rng.uniform(0.02, 0.05, 20_000))
    pos = np.stack([3.0 * t, -1.0 * t, 30.0 + 0.0 * t], axis=1)
    grid, rs = resample_uniform(t, pos, 1.0)
    assert np.allclose(np.diff(grid), 1.0)
    fit = fit_gauss_markov(velocities_from_positions(rs, 1.0), 1.0)
    assert fit.mean_horizontal_speed_mps == pytest.approx(np.hypot(3.0, 1.0), rel=1e-6)
    with pytest.raises(ValueError):
        fit_gauss_markov(np.zeros((2, 3)), 1.0)


def test_walk_starts_in_its_stationary_law():
    # No burn-in: a plan's first window already has the configured speed statistics.
    v0 = GaussMarkovMission(4000, GaussMarkovParams(min_separation_m=0.0), Area(), 8).velocities(0.0)
    assert v0[:, 2].var() == pytest.approx(3.713, rel=0.06)
    assert np.hypot(v0[:, 0], v0[:, 1]).mean() == pytest.approx(2.501, rel=0.04)
