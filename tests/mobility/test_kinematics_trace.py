"""kinematics() on known paths, and trace replay."""

from __future__ import annotations

import numpy as np
import pytest

from uavcas.mobility import Area, TraceMission, kinematics


def test_straight_climb():
    t = np.arange(0.0, 10.0, 0.5)
    p = np.stack([3 * t, 4 * t, 40 + 0.5 * t], axis=1)
    k = kinematics(p, t)
    assert np.allclose(k.horizontal_speed_mps, 5.0)
    assert np.allclose(k.vertical_speed_mps, 0.5)
    assert np.allclose(k.heading_rad, np.arctan2(4, 3))
    assert np.allclose(k.heading_rate_radps, 0.0)
    assert k.altitude_m.shape == (t.size,) and k.heading_rate_radps.shape == (t.size - 2,)


def test_circle_turn_rate_and_multi_uav_shapes():
    w = 0.2  # rad/s
    t = np.arange(0.0, 30.0, 0.1)
    ccw = np.stack([50 * np.cos(w * t), 50 * np.sin(w * t), 0 * t + 60], axis=1)
    cw = ccw * np.array([1, -1, 1])
    k = kinematics(np.stack([ccw, cw], axis=1), t)
    assert k.horizontal_speed_mps.shape == (t.size - 1, 2)
    assert np.allclose(k.heading_rate_radps[:, 0], w, rtol=1e-3)
    assert np.allclose(k.heading_rate_radps[:, 1], -w, rtol=1e-3)
    assert np.allclose(k.horizontal_speed_mps, 50 * w, rtol=1e-3)


def test_hover_has_zero_speed_and_no_spurious_turn():
    t = np.arange(5.0)
    p = np.array([[0, 0, 50], [10, 0, 50], [10, 0, 50], [10, 0, 50], [10, 10, 50]], dtype=float)
    k = kinematics(p, t)
    assert k.horizontal_speed_mps.tolist() == [10, 0, 0, 10]
    assert np.allclose(k.heading_rate_radps, 0.0)


def test_kinematics_refuses_bad_input():
    with pytest.raises(ValueError):
        kinematics(np.zeros((3, 2)), np.arange(3.0))
    with pytest.raises(ValueError):
        kinematics(np.zeros((3, 3)), np.array([0.0, 0.0, 1.0]))


def test_trace_interpolates_and_holds():
    t = np.array([100.0, 110.0, 130.0])
    p = np.array([[0, 0, 40], [100, 0, 40], [100, 200, 60]], dtype=float)
    m = TraceMission(t, p)
    assert m.n_uav == 1 and m.duration_s == 30.0
    assert np.allclose(m.positions(5.0), [[50, 0, 40]])
    assert np.allclose(m.positions(np.array([0.0, 20.0, 30.0, 99.0])),
                       [[[0, 0, 40]], [[100, 100, 50]], [[100, 200, 60]], [[100, 200, 60]]])


def test_trace_clips_to_the_area_only_when_asked():
    t = np.array([0.0, 1.0])
    p = np.array([[-5.0, 10, 20], [1200.0, 10, 20]])
    assert TraceMission(t, p).positions(0.0)[0, 2] == 20.0
    clipped = TraceMission(t, p, area=Area())
    assert clipped.clipped and Area().contains(clipped.positions(np.linspace(0, 1, 11)))


def test_trace_refuses_bad_input():
    with pytest.raises(ValueError):
        TraceMission(np.array([0.0, 0.0]), np.zeros((2, 3)))
    with pytest.raises(ValueError):
        TraceMission(np.array([0.0, 1.0]), np.zeros((3, 3)))
