"""Layer 1 on synthetic data with known parameters: budget recovery and path-loss fit."""

from __future__ import annotations

import numpy as np
import pytest

from uavcas.calibration.layer1_pathloss import (
    FSPL_1M_DB,
    fit_logdistance,
    layer1_json,
    prepare,
    run_layer1,
    two_ray_pattern_loss_db,
)
from uavcas.calibration.linkbudget import PatternGain, absolute_pathloss_db, recover_budget
from uavcas.calibration.loaders import load_maeng, load_multibw, load_pattern
from uavcas.channel import TwoRay

from .synthetic import TRUE_EIRP_DBM, TRUE_N, TRUE_PL0_DB, TRUE_SIGMA_DB, write_maeng, write_multibw


@pytest.fixture(scope="module")
def synth(tmp_path_factory):
    root = tmp_path_factory.mktemp("synth")
    truth = write_maeng(root, n=3000)
    write_multibw(root)
    return root, truth


def test_budget_recovers_eirp_and_absolute_pathloss(synth):
    root, truth = synth
    samples = load_maeng(root)
    pg = PatternGain(load_pattern(root))
    for s in samples:
        b = recover_budget(s, pg)
        assert b.eirp_eff_dbm == pytest.approx(TRUE_EIRP_DBM, abs=1e-6)
        assert b.pattern_residual_db == pytest.approx(0.0, abs=1e-6)
        assert b.tx_height_m == pytest.approx(10.0, abs=1e-6)
        # PL = EIRP + G - RSRP recovers the true loss sample by sample.
        np.testing.assert_allclose(absolute_pathloss_db(s), truth[int(s.altitude_m)]["_pl_true"], atol=1e-8)


@pytest.mark.parametrize("shared", [True, False])
def test_logdistance_fit_recovers_parameters(synth, shared):
    root, _ = synth
    samples = load_maeng(root)
    pg = PatternGain(load_pattern(root))
    groups = prepare(samples, [recover_budget(s, pg) for s in samples], seed=0)
    prof = fit_logdistance(groups, shared_intercept=shared)
    for i, h in enumerate(TRUE_N):
        assert prof.n[i] == pytest.approx(TRUE_N[h], abs=0.08 if shared else 0.2)
        assert prof.sigma_db[i] == pytest.approx(TRUE_SIGMA_DB[h], rel=0.08)
        assert prof.pl0_db[i] == pytest.approx(TRUE_PL0_DB, abs=1.5 if shared else 4.0)
    assert prof.altitude_m == tuple(sorted(prof.altitude_m))


def test_split_is_seeded_70_30(synth):
    root, _ = synth
    samples = load_maeng(root)
    a = prepare(samples, [recover_budget(s, None) for s in samples], seed=3)
    b = prepare(samples, [recover_budget(s, None) for s in samples], seed=3)
    c = prepare(samples, [recover_budget(s, None) for s in samples], seed=4)
    for ga, gb, gc in zip(a, b, c):
        assert np.array_equal(ga.train, gb.train) and not np.array_equal(ga.train, gc.train)
        assert ga.train.mean() == pytest.approx(0.7, abs=0.01)


def test_two_ray_pattern_weight_one_is_the_twins_two_ray():
    m = TwoRay(eps_r=12.0, conductivity_s_m=0.01)
    d2 = np.linspace(5, 600, 200)
    np.testing.assert_allclose(two_ray_pattern_loss_db(m, d2, 10.0, 50.0, 1.0), m.loss_db(d2, 10.0, 50.0), atol=1e-9)


def test_run_layer1_json_shape_and_checks(synth):
    root, _ = synth
    res = run_layer1(load_maeng(root), load_multibw(root), load_pattern(root), seed=0)
    j = layer1_json(res)
    for model in ("logdistance", "two_ray", "uma_av"):
        for split in ("heldout", "crossval"):
            assert set(j["models"][model][split]) >= {"rmse_db", "mae_db", "median_ae_db", "bias_db", "r"}
        assert set(j["models"][model]["per_altitude"]) == {"30", "50", "70", "90", "110"}
    assert abs(j["pl_at_1m_db"] - TRUE_PL0_DB) < 1.5
    assert abs(j["pl_at_1m_db"] - FSPL_1M_DB) < 10
    # Held-out RMSE of the fitted model is the noise level it was generated with.
    assert j["models"]["logdistance"]["heldout"]["rmse_db"] == pytest.approx(np.sqrt(np.mean(np.square(list(TRUE_SIGMA_DB.values())))), rel=0.1)
    assert j["checks"]["logdistance_beats_uma_av_heldout"]
