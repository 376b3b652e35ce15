"""`uavcas calibrate` CLI on synthetic data, and the written profile driving the twin's plan."""

from __future__ import annotations

import json
from types import SimpleNamespace

import numpy as np
import pytest
from typer.testing import CliRunner

from uavcas.calibration.pipeline import build_profile
from uavcas.channel import DEFAULT_PROFILE, LogDistance, PathLossProfile
from uavcas.cli import app
from uavcas.mobility import GridParams, MobilityProfile
from uavcas.twin import plan as make_plan
from uavcas.twin.profile import load_profile

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


def test_calibrate_pathloss_cli_writes_outputs_and_profile_that_changes_the_plan(tmp_path, profile_dir):
    data = tmp_path / "data"
    write_maeng(data, n=800)
    write_multibw(data)
    out = tmp_path / "out"
    r = CliRunner().invoke(app, ["calibrate", "pathloss", "--data", str(data), "--out", str(out), "--write-profile", "synthcal", "--seed", "1"])
    assert r.exit_code == 0, r.output
    for name in ("pathloss.json", "pathloss.md", "pathloss_vs_distance.png", "pathloss_crossval.png", "summary.md"):
        assert (out / name).stat().st_size > 0
    j = json.loads((out / "pathloss.json").read_text())
    assert set(j["models"]) >= {"logdistance", "two_ray", "uma_av"}
    assert j["models"]["logdistance"]["heldout"]["rmse_db"] > 0
    prof = load_profile("synthcal")
    fitted = prof.pathloss
    assert list(fitted.n) == pytest.approx(j["logdistance_params"]["n"])
    assert prof.mobility == MobilityProfile()  # mobility did not run: built-in kept

    base = make_plan(CONFIG, seed=5)
    cal = make_plan(CONFIG, seed=5, profile="synthcal")
    assert cal.profile == "synthcal"
    links_b = {k: (lk, h) for k, lk, h in _air_links(base)}
    links_c = {k: (lk, h) for k, lk, h in _air_links(cal)}
    assert links_b.keys() == links_c.keys() and links_b  # same geometry and routing
    diffs = []
    for k, (lb, h) in links_b.items():
        lc = links_c[k][0]
        # Same seed -> same unit shadowing Z; each profile scales it by its own sigma(h).
        d = lb.distance_m
        z = (lb.pathloss_db - LogDistance(DEFAULT_PROFILE).loss_db(d, h)) / DEFAULT_PROFILE.at(h)[2]
        expected = LogDistance(fitted).loss_db(d, h) + fitted.at(h)[2] * z
        assert lc.pathloss_db == pytest.approx(float(expected), abs=0.02)
        diffs.append(lc.snr_db - lb.snr_db)
    assert np.max(np.abs(diffs)) > 1.0  # the link parameters really moved


def test_written_mobility_profile_changes_the_plan(profile_dir):
    from uavcas.twin.profile import save_profile

    l2 = SimpleNamespace(profile=MobilityProfile(grid=GridParams(speed_mps=1.0, altitude_m=80.0)))
    prof = build_profile("mobcal", None, l2, data="synthetic", seed=0)
    assert prof.pathloss == DEFAULT_PROFILE
    save_profile(prof, "mobcal")
    base = make_plan(CONFIG, seed=2)
    cal = make_plan(CONFIG, seed=2, profile="mobcal")
    assert all(p[2] == 80.0 for w in cal.windows for n, p in w.positions.items() if n.startswith("uav"))
    assert base.windows[3].positions != cal.windows[3].positions


def test_cli_refuses_bad_input_with_one_line(tmp_path):
    r = CliRunner().invoke(app, ["calibrate", "pathloss", "--data", str(tmp_path), "--out", str(tmp_path / "o")])
    assert r.exit_code == 2 and "Maeng" in r.output
    r = CliRunner().invoke(app, ["calibrate", "everything", "--data", str(tmp_path), "--out", str(tmp_path / "o")])
    assert r.exit_code == 2 and "unknown layer" in r.output


def test_profile_json_roundtrip_of_fitted_pathloss():
    p = PathLossProfile(name="x", altitude_m=(26.7, 105.6), n=(2.1, 2.0), pl0_db=(43.5, 43.5), sigma_db=(6.7, 6.6))
    prof = build_profile("rt", SimpleNamespace(profile=p), None, data="d", seed=0)
    assert prof.pathloss.n == (2.1, 2.0) and prof.name == "rt"
