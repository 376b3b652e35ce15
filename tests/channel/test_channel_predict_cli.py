"""`uavcas channel predict`: every model against hand-computed values, the link chain columns,
and bad input refused with one line and nothing written."""

from __future__ import annotations

import os

import pandas as pd
import pytest
from typer.testing import CliRunner

from uavcas.channel import PathLossProfile
from uavcas.cli import app
from uavcas.twin.profile import PAPER_PROFILE

# (model, d3d, d2d, h_uav, h_bs, fc or None, expected mean path loss, tolerance, how it was computed)
CASES = [
    # Friis 20 log10(4 pi d f / c): 1 km at 3.51 GHz; 100 m at 2.4 GHz.
    ("freespace", 1000.0, 999.0, 60.0, 25.0, None, 103.354, 1e-3),
    ("freespace", 100.0, 99.0, 60.0, 25.0, 2.4, 80.05, 0.01),
    # TR 36.777 spec vector (UMa-AV, h 30 m, d2D 500 m, h_BS 25 m, 3.51 GHz): P_LOS 0.828456,
    # PL_LOS 98.2840, PL_NLOS 122.0944 -> 0.828456 * 98.2840 + 0.171544 * 122.0944 = 102.3685.
    ("3gpp", 500.025, 500.0, 30.0, 25.0, None, 102.3685, 2e-3),
    ("uma", 500.025, 500.0, 30.0, 25.0, None, 102.3685, 2e-3),
    # RMa-AV, h 60 m > 40 m: P_LOS = 1; (23.9 - 1.8 log10 60) log10 301.04 + 20 log10(40 pi 3.51 / 3)
    # = 20.6993 * 2.47862 + 43.3483 = 94.6538.
    ("rma", 301.0399, 300.0, 60.0, 35.0, None, 94.6538, 2e-3),
    # UMi-AV, h 60 m, d2D 50 m < d1 = 294.05 log10 60 - 432.94 = 89.93 m: P_LOS = 1;
    # max(FSPL 80.2958, 30.9 + (22.25 - 0.5 log10 60) log10 70.711 + 20 log10 3.51) = 81.3129.
    ("umi", 70.7107, 50.0, 60.0, 10.0, None, 81.3129, 2e-3),
    # Two-ray far beyond the crossover (4 ht hr / lambda = 35 km): 40 log10 d - 20 log10(ht hr).
    ("tworay", 400000.0, 400000.0, 30.0, 25.0, None, 40 * 5.60206 - 20 * 2.875061, 0.3),
]


@pytest.fixture()
def custom_profile(tmp_path):
    pl = PathLossProfile(name="ci", altitude_m=(50.0,), n=(2.5,), pl0_db=(40.0,), sigma_db=(4.0,), fc_ghz=3.51)
    path = tmp_path / "custom.json"
    path.write_text(PAPER_PROFILE.model_copy(update={"name": "custom", "pathloss": pl}).to_json())
    return path


def _run(tmp_path, rows, model, *extra):
    src, out = tmp_path / "geom.csv", tmp_path / "out.csv"
    pd.DataFrame(rows).to_csv(src, index=False)
    r = CliRunner().invoke(app, ["channel", "predict", "--model", model, "--in", str(src), "--out", str(out), *extra])
    return r, out


@pytest.mark.parametrize("case", CASES, ids=[f"{c[0]}-{i}" for i, c in enumerate(CASES)])
def test_every_model_matches_hand_computed_loss(tmp_path, case):
    model, d3, d2, hu, hb, fc, expected, tol = case
    row = {"d3d_m": d3, "d2d_m": d2, "h_uav_m": hu, "h_bs_m": hb, "link": "x"}
    if fc is not None:
        row["fc_ghz"] = fc
    r, out = _run(tmp_path, [row], model, "--profile", "paper", "--tx-dbm", "30", "--noise-dbm", "-90")
    assert r.exit_code == 0, r.output
    df = pd.read_csv(out)
    assert df["pathloss_db"][0] == pytest.approx(expected, abs=tol)
    assert df["snr_db"][0] == pytest.approx(30.0 - df["pathloss_db"][0] + 90.0, abs=1e-6)
    assert df["link"][0] == "x"  # other columns passed through


def test_logdist_uses_the_profile_and_its_carrier_anchor(tmp_path, custom_profile):
    rows = [{"d3d_m": 100.0, "d2d_m": 90.0, "h_uav_m": 50.0, "h_bs_m": 10.0, "fc_ghz": 3.51},
            {"d3d_m": 1000.0, "d2d_m": 999.0, "h_uav_m": 50.0, "h_bs_m": 10.0, "fc_ghz": 3.3}]
    r, out = _run(tmp_path, rows, "logdist", "--profile", str(custom_profile))
    assert r.exit_code == 0, r.output
    # 40 + 25 log10(100) = 90; 40 + 25 log10(1000) + 20 log10(3.3 / 3.51) = 115 - 0.53586.
    assert pd.read_csv(out)["pathloss_db"].tolist() == pytest.approx([90.0, 114.46414], abs=1e-4)


def test_link_chain_columns(tmp_path):
    rows = [{"d3d_m": 10.0, "d2d_m": 5.0, "h_uav_m": 40.0, "h_bs_m": 31.34},
            {"d3d_m": 3000.0, "d2d_m": 2999.0, "h_uav_m": 40.0, "h_bs_m": 10.0}]
    r, out = _run(tmp_path, rows, "freespace", "--profile", "paper")
    assert r.exit_code == 0, r.output
    df = pd.read_csv(out)
    # 10 m at 20 dBm: SNR = 20 - 63.354 + 95 = 51.65 dB -> 54 Mbit/s, the DCF rate 12000 / 393.5 us.
    assert df["mcs"][0] == 6 and df["rate_mbps"][0] == pytest.approx(12000 / 393.5, rel=0.005) and df["loss"][0] < 1e-4
    # 3 km: SNR = 20 - 112.9 + 95 = 2.1 dB, below MCS0's bound with the 5 dB implementation loss.
    assert df["mcs"][1] == 0 and df["loss"][1] > 0.99


@pytest.mark.parametrize("rows, needle", [
    ([{"d3d_m": 10.0, "d2d_m": 5.0, "h_uav_m": 40.0}], "missing column(s) h_bs_m"),
    ([{"d3d_m": "far", "d2d_m": 5.0, "h_uav_m": 40.0, "h_bs_m": 10.0}], "column d3d_m row 1"),
    ([{"d3d_m": 10.0, "d2d_m": -5.0, "h_uav_m": 40.0, "h_bs_m": 10.0}], "column d2d_m row 1: negative"),
    ([{"d3d_m": 10.0, "d2d_m": 50.0, "h_uav_m": 40.0, "h_bs_m": 10.0}],
     "row 1: d2d_m 50 exceeds d3d_m 10 by more than 0.5 m"),
    ([{"d3d_m": 10.0, "d2d_m": 5.0, "h_uav_m": 40.0, "h_bs_m": 10.0, "fc_ghz": 0.0}], "fc_ghz row 1"),
])
def test_bad_input_one_line_exit_2_nothing_written(tmp_path, rows, needle):
    r, out = _run(tmp_path, rows, "logdist")
    assert r.exit_code == 2 and needle in r.output and r.output.count("\n") <= 2
    assert not out.exists()


def test_a_rounding_error_in_d2d_is_clamped_and_counted(tmp_path):
    # positions rounded to the metre give d2d_m a little longer than d3d_m: clamped, counted on stderr
    rows = [{"d3d_m": 100.0, "d2d_m": 100.3, "h_uav_m": 10.0, "h_bs_m": 10.0},
            {"d3d_m": 100.0, "d2d_m": 100.0, "h_uav_m": 10.0, "h_bs_m": 10.0},
            {"d3d_m": 120.0, "d2d_m": 110.0, "h_uav_m": 60.0, "h_bs_m": 10.0}]
    r, out = _run(tmp_path, rows, "freespace")
    assert r.exit_code == 0, r.output
    assert "1 row(s) had d2d_m up to 0.5 m longer than d3d_m" in r.output
    df = pd.read_csv(out)
    assert df["d2d_m"].tolist() == [100.0, 100.0, 110.0]
    assert df["pathloss_db"][0] == pytest.approx(df["pathloss_db"][1])


def test_refuses_bad_model_profile_and_special_outputs(tmp_path):
    rows = [{"d3d_m": 10.0, "d2d_m": 5.0, "h_uav_m": 40.0, "h_bs_m": 10.0}]
    r, _ = _run(tmp_path, rows, "okumura")
    assert r.exit_code == 2 and "--model" in r.output
    r, _ = _run(tmp_path, rows, "logdist", "--profile", "nope")
    assert r.exit_code == 2 and "--profile" in r.output
    target = tmp_path / "keep.txt"
    target.write_text("mine")
    link = tmp_path / "out.csv"
    link.symlink_to(target)
    r, _ = _run(tmp_path, rows, "logdist")
    assert r.exit_code == 2 and "it is a symbolic link" in r.output
    assert link.is_symlink() and target.read_text() == "mine"
    link.unlink()
    os.mkfifo(link)
    r, _ = _run(tmp_path, rows, "logdist")
    assert r.exit_code == 2 and "it is a FIFO" in r.output
