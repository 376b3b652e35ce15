"""Small synthetic AERPAW-like files with KNOWN parameters, in the real files' formats."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import scipy.io

from uavcas.channel import free_space_loss_db

TRUE_EIRP_DBM = 6.0
TRUE_PL0_DB = 45.0  # shared intercept at 1 m
TRUE_N = {30: 2.3, 50: 2.2, 70: 2.1, 90: 2.0, 110: 1.9}
TRUE_SIGMA_DB = {30: 3.0, 50: 3.5, 70: 4.0, 90: 4.5, 110: 5.0}
TOWER_M = 10.0


def pattern_tables() -> dict:
    """A smooth, known pattern on the real file's grid (theta 90..-90, phi 180..-177)."""
    theta = np.arange(90.0, -90.1, -3.0)
    phi = np.r_[np.arange(180.0, -1.0, -3.0), np.arange(-3.0, -178.0, -3.0)]
    th, ph = np.meshgrid(theta, phi, indexing="ij")
    g_t = 3.0 * np.cos(np.radians(th)) + 1.0 * np.cos(np.radians(ph)) - 2.0
    g_r = -2.0 + 1.5 * np.sin(np.radians(th))
    return {"theta2": theta, "phi2": phi, "G_t_dB": g_t, "G_r_dB": g_r}


def maeng_table(h: int, n: int, rng: np.random.Generator) -> dict:
    d2 = rng.uniform(20.0, 500.0, n)
    height = np.full(n, float(h)) + rng.normal(0, 0.5, n)
    d3 = np.hypot(d2, height - TOWER_M)
    elev = np.arctan2(height - TOWER_M, d2)
    azim = rng.uniform(0.1, 2.8, n)
    ori = rng.uniform(-np.pi, np.pi, n)
    pl_true = TRUE_PL0_DB + 10 * TRUE_N[h] * np.log10(d3) + rng.normal(0, TRUE_SIGMA_DB[h], n)
    # Pattern gain with the convention linkbudget.PatternGain documents.
    from uavcas.calibration.linkbudget import PatternGain
    from uavcas.calibration.loaders import RadiationPattern

    t = pattern_tables()
    pg = PatternGain(RadiationPattern(Path("synthetic"), t["theta2"], t["phi2"], t["G_t_dB"], t["G_r_dB"]))
    g = pg.gain_db(elev, azim, ori)
    rsrp = TRUE_EIRP_DBM + g - pl_true
    pred_free = TRUE_EIRP_DBM + g - free_space_loss_db(d3, 3.51)
    return {
        "RSRP_s": rsrp, "RSRP_PL_free_s": pred_free, "RSRP_PL_two_s": pred_free, "dist_3D_s": d3,
        "dist_2D_new_s": d2, "height_s": height, "elev_s": elev, "azim_s": azim, "ori_s": ori,
        "sha_free_s": rsrp - pred_free, "_pl_true": pl_true,
    }


def write_maeng(root: Path, n: int = 600, seed: int = 0, fmt: str = "mat") -> dict[int, dict]:
    rng = np.random.default_rng(seed)
    out = {}
    folder = root / "data_gen" / "LTE_dataset" / "processed_data" if fmt == "mat" else root / "derived_csv"
    folder.mkdir(parents=True, exist_ok=True)
    for h in TRUE_N:
        t = maeng_table(h, n, rng)
        out[h] = t
        cols = {k: v for k, v in t.items() if not k.startswith("_")}
        if fmt == "mat":
            scipy.io.savemat(folder / f"filtererd_data_with_dist_ori_{h}_meas_rad.mat", cols)
        else:
            import pandas as pd

            pd.DataFrame(cols).to_csv(folder / f"lte_maeng_processed_{h}m.csv.gz", index=False)
    pat_dir = root / "data_gen" / "LTE_dataset"
    pat_dir.mkdir(parents=True, exist_ok=True)
    scipy.io.savemat(pat_dir / "rad_pat.mat", pattern_tables())
    return out


def write_multibw(root: Path, n: int = 400, seed: int = 1) -> None:
    rng = np.random.default_rng(seed)
    folder = root / "data_gen" / "Multi_BW_dataset" / "processed_data"
    folder.mkdir(parents=True, exist_ok=True)
    for h in (40, 70):
        d2 = rng.uniform(20.0, 450.0, n)
        height = np.full(n, float(h))
        d3 = np.hypot(d2, height - TOWER_M)
        k = 55.0 + rng.normal(0, 2.0, n)
        pl = TRUE_PL0_DB + 10 * 2.1 * np.log10(d3) + rng.normal(0, 4.0, n)
        scipy.io.savemat(folder / f"results_cole_with_tworay_tilt_src_alt_{h}m_fs20MHz.mat", {
            "power_all": k - pl, "RSRP_PL_free": k - free_space_loss_db(d3, 3.3), "dist_3D": d3, "dist_2D_new": d2, "h_all": height,
        })
