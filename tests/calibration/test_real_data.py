"""The calibration on the real AERPAW data (skipped when ../shared is absent).

One end-to-end run of `calibrate all` (about 1 min) feeds every assertion."""

from __future__ import annotations

import json

import numpy as np
import pytest

from uavcas.calibration.layer1_pathloss import FSPL_1M_DB
from uavcas.calibration.loaders import load_afar, load_maeng, load_multibw, load_pattern
from uavcas.calibration.pipeline import LAYERS, run

# a module fixture takes 115 s on 2 cores: the whole file is the full suite's
pytestmark = [pytest.mark.shared, pytest.mark.slow]


@pytest.fixture(scope="module")
def aerpaw(shared_data):
    return shared_data / "aerpaw"


@pytest.fixture(scope="module")
def calibrated(aerpaw, tmp_path_factory):
    out = tmp_path_factory.mktemp("cal")
    res = run(LAYERS, aerpaw, out, seed=0, log=lambda m: None)
    return out, res


def test_real_loaders(aerpaw):
    maeng = load_maeng(aerpaw)
    assert [s.altitude_m for s in maeng] == [30, 50, 70, 90, 110]
    assert all(17000 < len(s) < 18500 for s in maeng)
    assert sorted({s.altitude_m for s in load_multibw(aerpaw)}) == [40, 70, 100]
    assert load_pattern(aerpaw).g_tx_db.shape == (61, 120)
    flights = load_afar(aerpaw)
    assert len(flights) == 14 and all(f.rover_lon_lat is not None for f in flights)
    assert all(abs(f.rover_height_m - 1.5) < 0.1 for f in flights)


def test_real_csv_form_matches_mat(aerpaw, tmp_path):
    csv_only = tmp_path / "csv"
    csv_only.mkdir()
    src = aerpaw / "derived_csv" / "lte_maeng_processed_70m.csv.gz"
    (csv_only / src.name).symlink_to(src)
    a = next(s for s in load_maeng(aerpaw) if s.altitude_m == 70)
    b = load_maeng(csv_only)[0]
    assert b.source.name.endswith(".csv.gz") and len(a) == len(b)
    assert float(np.abs(a.rx_dbm - b.rx_dbm).max()) < 1e-9


def test_real_outputs_written(calibrated):
    out, res = calibrated
    for name in ("pathloss.json", "mobility.json", "link.json", "fidelity.json", "summary.md",
                 "pathloss_vs_distance.png",
                 "mobility_trajectories.png", "mobility_speed_cdf.png", "link_representative_flight.png",
                 "fidelity_rss_pdf.png"):
        assert (out / name).stat().st_size > 0, name
    assert res.runtime_s < 600


def test_real_pathloss_physical_and_beats_uma(calibrated):
    j = json.loads((calibrated[0] / "pathloss.json").read_text())
    assert j["pl_at_1m_db"] == pytest.approx(FSPL_1M_DB)  # close-in: anchored at the carrier
    ld, uma = j["models"]["logdistance"], j["models"]["uma_av"]
    for key in ("heldout_sample", "heldout_local_mean"):
        assert ld[key]["rmse_db"] < uma[key]["rmse_db"] and ld[key]["rmse_db"] < j["models"]["two_ray"][key]["rmse_db"]
    for model in ("logdistance", "two_ray", "uma_av"):
        for key in ("heldout_sample", "heldout_local_mean", "crossval_sample", "crossval_local_mean"):
            assert set(j["models"][model][key]) >= {"rmse_db", "mae_db", "median_ae_db", "bias_db", "r"}
    assert all(1.5 < n < 3.0 for n in j["logdistance_params"]["n"])
    # Issue #13 targets on the absolute scale (paper: 4.40 held-out, 7.04 cross-validation), met on
    # the 5 s local mean the twin's path loss stands for; per sample the fast fading alone is ~4.5 dB.
    assert ld["heldout_local_mean"]["rmse_db"] < 4.40 and ld["crossval_local_mean"]["rmse_db"] < 7.04
    # Per sample, 4.40 is out of reach of any log-distance fit on these samples (its least-squares
    # optimum on all of them is ~6.2 dB); only a per-sample split with flexible trees gets near it.
    c = j["ceiling"]
    assert c["logdistance_insample"]["rmse_db"] > 4.40 and c["geometry_gbm_heldout"]["rmse_db"] > 4.40
    assert c["geometry_gbm_paper_split"]["rmse_db"] < c["geometry_gbm_heldout"]["rmse_db"] - 1.0
    assert ld["heldout_sample"]["rmse_db"] > c["logdistance_insample"]["rmse_db"]
    assert 9.0 < j["tx_height_m"] < 12.5  # the AERPAW LW1 tower is 10-12 m
    assert all(3.0 < k < 9.0 for k in j["k_factor_db"]["k_db"])
    assert 20.0 < j["shadowing_decorrelation_m"] < 150.0


def test_real_mobility_and_fidelity_bounded(calibrated):
    out = calibrated[0]
    m = json.loads((out / "mobility.json").read_text())
    assert set(m["missions"]) == {"spiral", "grid", "hover_transit", "random"}
    paper = {"spiral": 0.32, "grid": 0.65, "hover_transit": 0.26, "random": 0.16}
    for k, v in m["missions"].items():
        assert 0.0 <= v["heldout"]["jsd_speed"] <= 1.0 and v["params"]
        assert v["heldout"]["jsd_speed"] <= v["heldout"]["js_distance_speed"] <= 1.0  # distance = sqrt(divergence)
        assert v["heldout"]["jsd_speed"] <= paper[k]  # issue #13: divergence at or below the paper's figures
    f = json.loads((out / "fidelity.json").read_text())
    assert all(0.0 <= h <= 1.0 for h in f["hellinger"].values())
    link = json.loads((out / "link.json").read_text())
    assert not set(link["train_flights"]) & set(link["test_flights"])
    assert link["variants"]["logdistance"]["median_ae_db"] < 20.0
