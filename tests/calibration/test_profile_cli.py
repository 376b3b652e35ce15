"""`uavcas calibrate` CLI on synthetic data, and the written profile driving the twin's plan."""

from __future__ import annotations

import hashlib
import json
from types import SimpleNamespace

import numpy as np
import pytest
from typer.testing import CliRunner

from uavcas import __version__
from uavcas.calibration.pipeline import build_profile
from uavcas.channel import PAPER_ANCHORED_PROFILE, KFactorProfile, LogDistance, PathLossProfile
from uavcas.cli import app
from uavcas.mobility import GridParams, MobilityProfile
from uavcas.twin.plan import plan as make_plan
from uavcas.twin.profile import PAPER_PROFILE, ProfileError, load_profile, profile_sha256, save_profile

from .synthetic import write_maeng, write_multibw

CONFIG = "benign-6-2-image-logdist-adaptive-grid-30-95"


@pytest.fixture()
def profile_dir(tmp_path, monkeypatch):
    d = tmp_path / "profiles"
    monkeypatch.setenv("UAVCAS_PROFILE_DIR", str(d))
    return d


def _air_links(p):
    nodes = {n.name: n.kind for n in p.nodes}
    for w in p.windows:
        for lk in w.links:
            if lk.kind == "air":
                za, zb = w.positions[lk.a][2], w.positions[lk.b][2]
                if nodes[lk.a] == "bs":
                    h = zb
                elif nodes[lk.b] == "bs":
                    h = za
                else:
                    h = max(za, zb)
                yield (w.index, lk.a, lk.b), lk, h


@pytest.mark.slow  # 4 s on 2 cores
def test_calibrate_pathloss_cli_writes_outputs_and_a_profile_with_provenance(tmp_path, profile_dir):
    data = tmp_path / "data"
    write_maeng(data, n=3000)
    write_multibw(data)
    out = tmp_path / "out"
    r = CliRunner().invoke(app, ["calibrate", "pathloss", "--data", str(data), "--out", str(out), "--write-profile",
                                 "synthcal", "--seed", "1"])
    assert r.exit_code == 0, r.output
    for name in ("pathloss.json", "pathloss.md", "pathloss_vs_distance.png", "pathloss_crossval.png", "summary.md"):
        assert (out / name).stat().st_size > 0
    j = json.loads((out / "pathloss.json").read_text())
    assert set(j["models"]) >= {"logdistance", "two_ray", "uma_av"}
    prof = load_profile("synthcal")
    assert list(prof.pathloss.n) == pytest.approx(j["logdistance_params"]["n"])
    assert prof.mobility == MobilityProfile()  # mobility did not run: the paper's kept
    assert prof.bs_mast_m == pytest.approx(10.0)  # the synthetic tower
    assert list(prof.channel.fading.k_db) == pytest.approx(j["k_factor_db"]["k_db"])
    assert prof.channel.d_corr_m == pytest.approx(j["shadowing_decorrelation_m"], abs=0.05)
    pv = prof.provenance
    assert pv.uavcas_version == __version__ and pv.seed == 1 and pv.fit_date_utc.endswith("+00:00")
    files = {f.path: f for f in pv.data_files}
    mat = next(p for p in files if p.endswith("filtererd_data_with_dist_ori_30_meas_rad.mat"))
    assert files[mat].sha256 == hashlib.sha256((data / mat).read_bytes()).hexdigest()
    assert any(p.endswith("rad_pat.mat") for p in files) and any("alt_70m" in p for p in files)
    # The profile drives the plan and is recorded in it by name and hash.
    p = make_plan(CONFIG, seed=5, profile="synthcal")
    assert p.profile == "synthcal" and p.profile_sha256 == profile_sha256(prof)


def test_fitted_pathloss_changes_the_links_as_its_numbers_say(tmp_path):
    fitted = PathLossProfile(name="f", altitude_m=(30.0, 110.0), n=(2.3, 2.0), pl0_db=(43.35, 43.35),
                             sigma_db=(3.0, 5.0))
    base_prof = PAPER_PROFILE.model_copy(update={"name": "a"})
    cal_prof = PAPER_PROFILE.model_copy(update={"name": "b", "pathloss": fitted})
    base, cal = make_plan(CONFIG, seed=5, profile=base_prof), make_plan(CONFIG, seed=5, profile=cal_prof)
    links_b = {k: (lk, h) for k, lk, h in _air_links(base)}
    links_c = {k: (lk, h) for k, lk, h in _air_links(cal)}
    # Same geometry; the routing follows link quality, so the profiles may pick a few other links.
    common = sorted(links_b.keys() & links_c.keys())
    assert links_b and len(common) >= 0.5 * len(links_b)
    diffs = []
    for k in common:
        (lb, h), lc = links_b[k], links_c[k][0]
        # Same seed -> same unit shadowing Z; each profile scales it by its own sigma(h).
        d = lb.distance_m
        z = (lb.pathloss_db - LogDistance(PAPER_ANCHORED_PROFILE).loss_at_db(d, h)) / PAPER_ANCHORED_PROFILE.at(h)[2]
        expected = LogDistance(fitted).loss_at_db(d, h) + fitted.at(h)[2] * z
        assert lc.pathloss_db == pytest.approx(float(expected), abs=0.02)
        diffs.append(lc.snr_db - lb.snr_db)
    assert np.max(np.abs(diffs)) > 1.0  # the link parameters really moved


def test_written_mobility_profile_changes_the_plan(profile_dir):
    l2 = SimpleNamespace(profile=MobilityProfile(grid=GridParams(speed_mps=1.0, altitude_m=80.0)))
    prof = build_profile("mobcal", None, l2, data="synthetic", seed=0)
    assert prof.pathloss == PAPER_ANCHORED_PROFILE and prof.provenance is None
    save_profile(prof, "mobcal")
    base = make_plan(CONFIG, seed=2, profile="paper")
    cal = make_plan(CONFIG, seed=2, profile="mobcal")
    assert all(p[2] == 80.0 for w in cal.windows for n, p in w.positions.items() if n.startswith("uav"))
    assert base.windows[3].positions != cal.windows[3].positions


def test_built_in_names_and_hashes(profile_dir, tmp_path):
    default, cal, paper = load_profile(None), load_profile("calibrated"), load_profile("paper")
    assert default is cal and paper is PAPER_PROFILE and default.name == "calibrated"
    assert profile_sha256(cal) == hashlib.sha256(cal.to_json().encode()).hexdigest() != profile_sha256(paper)
    with pytest.raises(ProfileError, match="built in"):
        save_profile(paper, "paper")
    path = save_profile(paper.model_copy(update={"name": "x"}), str(tmp_path / "mine.json"))
    assert load_profile(str(path)).name == "mine"
    with pytest.raises(ProfileError, match="not found"):
        load_profile("nope")


def test_cli_refuses_bad_input_with_one_line(tmp_path):
    r = CliRunner().invoke(app, ["calibrate", "pathloss", "--data", str(tmp_path), "--out", str(tmp_path / "o")])
    assert r.exit_code == 2 and "Maeng" in r.output
    r = CliRunner().invoke(app, ["calibrate", "everything", "--data", str(tmp_path), "--out", str(tmp_path / "o")])
    assert r.exit_code == 2 and "LAYER: 'everything' is not one of" in r.output and r.output.count("\n") == 1


def test_profile_json_roundtrip_of_fitted_pathloss():
    p = PathLossProfile(name="x", altitude_m=(26.7, 105.6), n=(2.1, 2.0), pl0_db=(43.5, 43.5), sigma_db=(6.7, 6.6))
    k = KFactorProfile(name="k", altitude_m=(26.7, 105.6), k_db=(5.4, 5.6))
    l1 = SimpleNamespace(profile=p, tx_height_m=10.04, k_factor=k, decorrelation_m=55.4)
    prof = build_profile("rt", l1, None, data="d", seed=0)
    assert prof.pathloss.n == (2.1, 2.0) and prof.name == "rt" and prof.bs_mast_m == 10.04
    assert prof.area.z_min_m == 26.7 and prof.area.z_max_m == 110.0  # down to the lowest calibrated altitude
    assert prof.channel.fading == k and prof.channel.d_corr_m == 55.4
    assert type(prof).model_validate_json(prof.to_json()) == prof
