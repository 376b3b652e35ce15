"""Path-loss models: TR 36.777 spec vectors, profile interpolation, physical anchors, shapes."""

from __future__ import annotations

import json

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from uavcas.channel.geometry import LinkGeometry
from uavcas.channel.pathloss import (
    PAPER_ANCHORED_PROFILE,
    PAPER_RELATIVE_PROFILE,
    FreeSpace,
    LogDistance,
    PathLossProfile,
    RMaAV,
    TwoRay,
    UMaAV,
    UMiAV,
    free_space_loss_db,
    make_pathloss,
)

# --- TR 36.777 Annex B spec vectors (fc 3.51 GHz, h_BS 25 m) ---------------------------------


def test_uma_av_spec_vectors_h30():
    m = UMaAV(fc_ghz=3.51, h_bs_m=25.0)
    d3d = np.hypot(500.0, 30.0 - 25.0)
    assert d3d == pytest.approx(500.02, abs=0.01)
    assert m.p_los_at(np.array([500.0]), np.array([30.0]))[0] == pytest.approx(0.828456, abs=1e-5)
    assert m.loss_los_db(np.array([d3d]), np.array([30.0]))[0] == pytest.approx(98.2840, abs=1e-3)
    assert m.loss_nlos_db(np.array([d3d]), np.array([30.0]))[0] == pytest.approx(122.0944, abs=1e-3)


def test_uma_av_spec_vectors_h70_h110():
    m = UMaAV(fc_ghz=3.51, h_bs_m=25.0)
    assert float(m.p_los_at(500.0, 70.0)) == pytest.approx(0.919969, abs=1e-5)
    assert float(m.loss_los_db(m.d3d_m(500.0, 70.0), 70.0)) == pytest.approx(98.3220, abs=1e-3)
    assert float(m.p_los_at(500.0, 110.0)) == 1.0
    assert np.all(m.p_los_at(np.array([20.0, 500.0, 4000.0]), 110.0) == 1.0)


def test_uma_av_sigma_and_arrays_broadcast():
    m = UMaAV()
    sig = m.sigma_los_db(np.array([30.0, 110.0]))
    np.testing.assert_allclose(sig, 4.64 * np.exp(-0.0066 * np.array([30.0, 110.0])))
    assert m.sigma_nlos_db(np.array([30.0, 70.0])).tolist() == [6.0, 6.0]
    p = m.p_los_at(np.array([10.0, 500.0, 1000.0]), np.array([[30.0], [70.0]]))
    assert p.shape == (2, 3)
    assert m.loss_los_db(np.array([100.0, 200.0]), np.array([30.0, 60.0])).shape == (2,)


def test_rma_av_values():
    # Hand-computed from TR 36.777 Table B-1/B-2 (arithmetic in the comments).
    m = RMaAV(fc_ghz=2.0)
    # LOS, h 50 m, d3D 1 km, 2 GHz: 20.842 * 3 + 20 log10(40 pi 2 / 3) = 100.988 dB
    assert float(m.loss_los_db(1000.0, 50.0)) == pytest.approx(100.988, abs=1e-3)
    m = RMaAV(fc_ghz=3.51)
    # P_LOS h 30 m, d2D 2 km: d1 = 393.30, p1 = 6134.84 -> 0.776508
    assert float(m.p_los_at(2000.0, 30.0)) == pytest.approx(0.776508, abs=1e-5)
    assert float(m.p_los_at(2000.0, 41.0)) == 1.0  # h > 40 m: always LOS
    # NLOS h 30 m, d3D 2 km = max(113.466, 121.041)
    assert float(m.loss_nlos_db(2000.0, 30.0)) == pytest.approx(121.041, abs=1e-3)
    assert float(m.sigma_los_db(30.0)) == pytest.approx(3.6586, abs=1e-4)


def test_umi_av_values():
    m = UMiAV(fc_ghz=3.51, h_bs_m=10.0)
    # P_LOS h 50 m, d2D 500 m: d1 = 66.642, p1 = 396.575 -> 0.378936
    assert float(m.p_los_at(500.0, 50.0)) == pytest.approx(0.378936, abs=1e-5)
    d3d = float(m.d3d_m(500.0, 50.0))
    assert float(m.loss_los_db(d3d, 50.0)) == pytest.approx(99.5951, abs=1e-3)  # > free space 97.31
    assert float(m.loss_nlos_db(d3d, 50.0)) == pytest.approx(125.0940, abs=1e-3)
    assert float(m.sigma_los_db(50.0)) == pytest.approx(3.0327, abs=1e-4)
    assert float(m.sigma_los_db(250.0)) == 2.0  # floor of max(5 exp(-0.01 h), 2)
    assert float(m.sigma_nlos_db(50.0)) == 8.0
    # LOS never below free space (Table B-2 note): at short range the FS branch wins.
    d = np.geomspace(1.0, 3000.0, 50)
    assert np.all(m.loss_los_db(d, 300.0) >= 32.4 + 20 * np.log10(3.51) + 20 * np.log10(d) - 1e-9)


@pytest.mark.parametrize("cls", [UMaAV, RMaAV, UMiAV])
def test_expected_loss_and_sampling(cls):
    m = cls(fc_ghz=3.51)
    d2d, h = np.full(20000, 800.0), np.full(20000, 30.0)
    d3d = m.d3d_m(d2d, h)
    los, nlos = m.loss_los_db(d3d, h), m.loss_nlos_db(d3d, h)
    exp = m.loss_expected_db(d2d, d3d, h)
    assert np.all(exp >= los - 1e-9) and np.all(exp <= nlos + 1e-9)
    u = np.random.default_rng(3).random(20000)
    s = m.sample(d2d, d3d, h, u)
    p = float(m.p_los_at(800.0, 30.0))
    assert s.los.mean() == pytest.approx(p, abs=0.015)
    np.testing.assert_allclose(s.loss_db[s.los], los[s.los])
    np.testing.assert_allclose(s.loss_db[~s.los], nlos[~s.los])
    assert np.all(s.sigma_db[~s.los] == m.sigma_nlos_db(30.0))


def test_evaluate_on_ground_to_air_geometry():
    m = UMaAV()
    geom = LinkGeometry.ground_to_air(np.array([100.0, 500.0]), np.array([30.0, 70.0]), 25.0)
    np.testing.assert_allclose(geom.d3d_m, np.hypot([100.0, 500.0], [5.0, 45.0]))
    res = m.evaluate(geom)
    np.testing.assert_allclose(res.loss_db, m.loss_expected_db(geom.d2d_m, geom.d3d_m, geom.h_air_m))
    sampled = m.evaluate(geom, los_uniform=np.array([0.0, 0.9999]))
    assert sampled.los.tolist() == [True, False]
    # Log-distance, two-ray and free space give finite losses on the same geometry.
    for name in ("logdist", "tworay", "freespace", "rma", "umi"):
        out = make_pathloss(name).evaluate(geom)
        assert out.loss_db.shape == (2,) and np.all(np.isfinite(out.loss_db)) and np.all(out.sigma_db >= 0)


@settings(max_examples=60, deadline=None)
@given(
    h=st.floats(30.0, 110.0),
    d1=st.floats(1.0, 2000.0),
    d2=st.floats(1.0, 2000.0),
    name=st.sampled_from(["uma", "rma", "umi"]),
)
def test_aerial_monotone_in_distance(h, d1, d2, name):
    m = make_pathloss(name)
    lo, hi = sorted((d1, d2))
    assert m.p_los_at(hi, h) <= m.p_los_at(lo, h) + 1e-12
    assert 0.0 < m.p_los_at(hi, h) <= 1.0
    assert m.loss_los_db(hi, h) >= m.loss_los_db(lo, h)
    assert m.loss_nlos_db(hi, h) >= m.loss_nlos_db(lo, h)


def test_air_to_air_links_are_los_in_3gpp():
    m = UMaAV()
    geom = LinkGeometry(
        d3d_m=np.array([600.0, 600.0]), d2d_m=np.array([600.0, 600.0]),
        h_ground_m=np.array([25.0, 30.0]), h_air_m=np.array([30.0, 30.0]),
        air_to_air=np.array([False, True]),
    )
    res = m.evaluate(geom, los_uniform=np.array([0.999, 0.999]))
    assert res.los.tolist() == [False, True]
    assert res.loss_db[1] == pytest.approx(float(m.loss_los_db(600.0, 30.0)))
    mean = m.evaluate(geom)  # no draw: probability-weighted mean
    assert mean.los is None and mean.loss_db[0] > mean.loss_db[1]


# --- log-distance profiles -----------------------------------------------------------------


def test_default_profile_is_anchored_at_free_space():
    fspl_1m = float(free_space_loss_db(1.0, 3.51))
    assert fspl_1m == pytest.approx(43.35, abs=0.01)
    assert min(PAPER_ANCHORED_PROFILE.pl0_db) == pytest.approx(fspl_1m, abs=1e-3)
    # The paper's per-altitude differences are kept (one common offset).
    diff = np.array(PAPER_ANCHORED_PROFILE.pl0_db) - np.array(PAPER_RELATIVE_PROFILE.pl0_db)
    np.testing.assert_allclose(diff, diff[0], atol=1e-3)
    assert PAPER_ANCHORED_PROFILE.n == (1.541, 1.593, 1.849, 1.881, 1.860)
    assert PAPER_ANCHORED_PROFILE.sigma_db == (3.70, 3.73, 4.08, 4.48, 4.46)


def test_profile_interpolates_and_clamps():
    n, pl0, sig = PAPER_ANCHORED_PROFILE.at(np.array([40.0, 10.0, 30.0, 110.0, 500.0]))
    assert n[0] == pytest.approx((1.541 + 1.593) / 2)
    assert sig[0] == pytest.approx((3.70 + 3.73) / 2)
    assert n[1] == n[2] == 1.541 and pl0[1] == pl0[2]  # clamped below 30 m
    assert n[3] == n[4] == 1.860 and sig[4] == 4.46  # clamped above 110 m


def test_logdistance_formula_and_monotone():
    m = LogDistance()
    d = np.array([1.0, 10.0, 100.0, 700.0])
    loss = m.loss_at_db(d, 70.0)
    np.testing.assert_allclose(loss, PAPER_ANCHORED_PROFILE.pl0_db[2] + 18.49 * np.log10(d))
    assert np.all(np.diff(m.loss_at_db(np.geomspace(1, 2000, 100), 55.0)) > 0)
    assert float(m.loss_at_db(0.2, 70.0)) == float(m.loss_at_db(1.0, 70.0))  # floored at d0


def test_profile_json_round_trip_and_validation():
    text = PAPER_ANCHORED_PROFILE.model_dump_json()
    assert PathLossProfile.model_validate_json(text) == PAPER_ANCHORED_PROFILE
    assert json.loads(text)["name"] == "paper-anchored"
    with pytest.raises(ValueError):
        PathLossProfile(name="x", altitude_m=(50.0, 30.0), n=(2, 2), pl0_db=(40, 40), sigma_db=(1, 1))
    with pytest.raises(ValueError):
        PathLossProfile(name="x", altitude_m=(30.0,), n=(2, 2), pl0_db=(40,), sigma_db=(1,))


# --- free space, two-ray, factory ----------------------------------------------------------


def test_free_space_friis():
    # 1 km at 3.51 GHz: 20 log10(4 pi 1000 / 0.085410) = 103.3539 dB
    assert float(FreeSpace().loss_at_db(1000.0)) == pytest.approx(103.354, abs=1e-3)
    assert float(FreeSpace(fc_ghz=2.4).loss_at_db(100.0)) == pytest.approx(80.05, abs=0.01)


@pytest.mark.parametrize("pol", ["vertical", "horizontal"])
def test_two_ray_limits(pol):
    m = TwoRay(polarisation=pol)
    assert abs(complex(m.reflection_coefficient(1e-6)) + 1.0) < 1e-3  # grazing: Gamma -> -1
    # Far beyond the crossover distance 4 ht hr / lambda (35 km here), PL -> 40 log d - 20 log(ht hr).
    d = np.array([4e5, 8e5])
    far = m.loss_at_db(d, 25.0, 30.0)
    np.testing.assert_allclose(far, 40 * np.log10(d) - 20 * np.log10(25.0 * 30.0), atol=0.3)
    # Coherent sum stays within [-6 dB, +inf) of free space; it oscillates around it up close.
    near = np.linspace(20.0, 600.0, 400)
    fs = free_space_loss_db(np.hypot(near, 5.0))
    two = m.loss_at_db(near, 25.0, 30.0)
    assert np.all(two >= fs - 6.03) and np.ptp(two - fs) > 6.0


def test_make_pathloss_names():
    assert isinstance(make_pathloss("3gpp"), UMaAV) and isinstance(make_pathloss("uma"), UMaAV)
    assert isinstance(make_pathloss("rma"), RMaAV) and isinstance(make_pathloss("umi"), UMiAV)
    assert isinstance(make_pathloss("tworay"), TwoRay)
    assert isinstance(make_pathloss("freespace"), FreeSpace)
    assert make_pathloss("logdist", profile="paper-relative").profile is PAPER_RELATIVE_PROFILE
    assert make_pathloss("3gpp", h_bs_m=30.0).h_bs_m == 30.0
    with pytest.raises(ValueError, match="unknown path-loss model"):
        make_pathloss("okumura")
    with pytest.raises(ValueError, match="unknown path-loss profile"):
        make_pathloss("logdist", profile="nope")


def test_logdistance_carrier_anchor_moves_the_curve_by_friis():
    # Close-in model at 3.51 GHz: PL(d) = 43.354 + 10 n log10 d; at 3.3 GHz the whole curve
    # moves by 20 log10(3.3 / 3.51) = -0.5359 dB (hand-computed), the slope unchanged.
    p = PathLossProfile(name="ci", altitude_m=(50.0,), n=(2.1,), pl0_db=(43.3539,), sigma_db=(4.0,), fc_ghz=3.51)
    d = np.array([10.0, 100.0, 500.0])
    at_351 = LogDistance(p).loss_at_db(d, 50.0)
    np.testing.assert_allclose(at_351, 43.3539 + 21.0 * np.log10(d))
    at_33 = LogDistance(p, fc_ghz=3.3).loss_at_db(d, 50.0)
    np.testing.assert_allclose(at_33 - at_351, -0.53586, atol=1e-4)
    assert make_pathloss("logdist", profile=p, fc_ghz=3.3).carrier_shift_db == pytest.approx(-0.53586, abs=1e-4)
    assert make_pathloss("logdist", profile=p).carrier_shift_db == 0.0  # None: the profile's own carrier
