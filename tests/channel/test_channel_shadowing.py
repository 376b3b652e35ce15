"""Gudmundson AR(1) shadowing: stationary sigma, exp(-d/d_corr) correlation, determinism."""

from __future__ import annotations

import numpy as np
import pytest

from uavcas.channel.shadowing import GudmundsonShadowing, correlation


def _walk(n_nodes: int, steps: int, step_m: float, moving: np.ndarray) -> np.ndarray:
    """Positions (steps, n, 3): `moving` nodes advance step_m along x each step."""
    start = np.random.default_rng(0).uniform(0, 1000, (n_nodes, 3))
    k = np.arange(steps)[:, None, None]
    return start + k * step_m * np.array([1.0, 0, 0]) * moving[None, :, None]


def _series(sh: GudmundsonShadowing, track: np.ndarray, pairs: np.ndarray) -> np.ndarray:
    out = []
    for pos in track:
        sh.step(pos)
        out.append(sh.unit(pairs))
    return np.array(out)  # (steps, k)


def test_marginal_sigma_and_mean():
    n = 40
    moving = np.ones(n, bool)
    sh = GudmundsonShadowing(n, d_corr_m=50.0, seed=11)
    iu = np.triu_indices(n, 1)
    pairs = np.c_[iu]
    z = _series(sh, _walk(n, 60, 10.0, moving), pairs)
    x = 4.0 * z  # sigma 4 dB
    assert x.std() == pytest.approx(4.0, rel=0.03)
    assert abs(x.mean()) < 0.1


@pytest.mark.parametrize("step_m", [10.0, 25.0, 50.0])
def test_lag_correlation_is_exponential(step_m):
    # Node 0 is a fixed BS, the others move step_m per window: each BS link has dd = step_m.
    n = 400
    moving = np.ones(n, bool)
    moving[0] = False
    sh = GudmundsonShadowing(n, d_corr_m=50.0, seed=5)
    pairs = np.c_[np.zeros(n - 1, int), np.arange(1, n)]
    z = _series(sh, _walk(n, 40, step_m, moving), pairs)
    for lag in (1, 2, 4):
        a, b = z[:-lag].ravel(), z[lag:].ravel()
        r = np.corrcoef(a, b)[0, 1]
        expected = float(correlation(lag * step_m, 50.0))
        assert r == pytest.approx(expected, abs=0.03), (lag, r, expected)


def test_both_ends_moving_add_their_displacements():
    # UAV-UAV pairs where both move 10 m: dd = 20 m -> rho = exp(-0.4), not exp(-0.2) and not 1
    # (their relative vector never changes).
    n = 300
    sh = GudmundsonShadowing(n, d_corr_m=50.0, seed=9)
    pairs = np.c_[np.arange(0, n, 2), np.arange(1, n, 2)]
    z = _series(sh, _walk(n, 40, 10.0, np.ones(n, bool)), pairs)
    r = np.corrcoef(z[:-1].ravel(), z[1:].ravel())[0, 1]
    assert r == pytest.approx(np.exp(-20.0 / 50.0), abs=0.03)


def test_static_nodes_keep_their_shadowing():
    sh = GudmundsonShadowing(3, seed=1)
    pos = np.zeros((3, 3)) + np.arange(3)[:, None]
    sh.step(pos)
    first = sh.unit(np.array([[0, 1], [1, 2]]))
    sh.step(pos)
    np.testing.assert_array_equal(sh.unit(np.array([[0, 1], [1, 2]])), first)


def test_seeded_deterministic_and_symmetric():
    track = _walk(6, 5, 7.0, np.ones(6, bool))
    pairs = np.array([[0, 1], [4, 2], [5, 3]])
    a = _series(GudmundsonShadowing(6, seed=123), track, pairs)
    b = _series(GudmundsonShadowing(6, seed=123), track, pairs)
    c = _series(GudmundsonShadowing(6, seed=124), track, pairs)
    np.testing.assert_array_equal(a, b)
    assert not np.allclose(a, c)
    sh = GudmundsonShadowing(6, seed=123)
    sh.step(track[0])
    np.testing.assert_array_equal(sh.unit(np.array([[1, 0], [2, 4]])), sh.unit(np.array([[0, 1], [4, 2]])))


def test_call_scales_by_sigma_and_validates():
    sh = GudmundsonShadowing(3, seed=0)
    pos = np.zeros((3, 3))
    x = sh(pos, np.array([[0, 1], [0, 2]]), np.array([2.0, 0.0]))
    assert x[1] == 0.0 and x[0] == pytest.approx(2.0 * sh.unit(np.array([[0, 1]]))[0])
    with pytest.raises(ValueError):
        sh.step(np.zeros((4, 3)))
    with pytest.raises(ValueError):
        sh.unit(np.array([[1, 1]]))
    with pytest.raises(RuntimeError):
        GudmundsonShadowing(2).unit(np.array([[0, 1]]))
