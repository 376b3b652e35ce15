"""Small synthetic AERPAW-like files with KNOWN parameters, in the real files' formats.

Maeng-like: per altitude a 10 Hz survey flight (lawn-mower lanes at 3.4 m/s) with close-in
log-distance path loss, Gudmundson shadowing along the path, Rician fading per sample and a
known airframe gain error on top of the pattern table."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import scipy.io

from uavcas.channel import free_space_loss_db

TRUE_EIRP_DBM = 6.0
TRUE_PL0_DB = float(free_space_loss_db(1.0, 3.51))  # close-in: free space at 1 m
TRUE_N = {30: 2.3, 50: 2.2, 70: 2.1, 90: 2.0, 110: 1.9}
TRUE_SIGMA_DB = {30: 3.0, 50: 3.5, 70: 4.0, 90: 4.5, 110: 5.0}  # local-mean shadowing
TRUE_K_DB = 6.0  # Rician K of the per-sample fading
TRUE_DCORR_M = 50.0
TRUE_AIRFRAME_DB = 2.0  # gain error of the pattern table: + A cos(body azimuth)
TOWER_M = 10.0
SPEED_MPS = 3.4  # Maeng-like survey: 10 Hz samples, lanes 50 m apart


def pattern_tables() -> dict:
    """A smooth, known pattern on the real file's grid (theta 90..-90, phi 180..-177)."""
    theta = np.arange(90.0, -90.1, -3.0)
    phi = np.r_[np.arange(180.0, -1.0, -3.0), np.arange(-3.0, -178.0, -3.0)]
    th, ph = np.meshgrid(theta, phi, indexing="ij")
    g_t = 3.0 * np.cos(np.radians(th)) + 1.0 * np.cos(np.radians(ph)) - 2.0
    g_r = -2.0 + 1.5 * np.sin(np.radians(th))
    return {"theta2": theta, "phi2": phi, "G_t_dB": g_t, "G_r_dB": g_r}


def survey_track(n: int, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    """(xy (n, 2), heading (n,)) of a lawn-mower survey flown at SPEED_MPS, sampled at 10 Hz."""
    lanes = []
    for k, y in enumerate(np.arange(40.0, 400.0, 50.0)):
        lanes += [(-300.0, y), (450.0, y)] if k % 2 == 0 else [(450.0, y), (-300.0, y)]
    v = np.asarray(lanes)
    seg = np.linalg.norm(np.diff(v, axis=0), axis=1)
    cum = np.r_[0.0, np.cumsum(seg)]
    s = (rng.uniform(0, cum[-1]) + SPEED_MPS * 0.1 * np.arange(n)) % cum[-1]
    xy = np.c_[np.interp(s, cum, v[:, 0]), np.interp(s, cum, v[:, 1])]
    k = np.minimum(np.searchsorted(cum, s, side="right") - 1, len(seg) - 1)
    d = v[k + 1] - v[k]
    return xy, np.arctan2(d[:, 1], d[:, 0])


def maeng_table(h: int, n: int, rng: np.random.Generator) -> dict:
    xy, heading = survey_track(n, rng)
    d2 = np.hypot(xy[:, 0], xy[:, 1])
    height = np.full(n, float(h)) + rng.normal(0, 0.5, n)
    d3 = np.hypot(d2, height - TOWER_M)
    elev = np.arctan2(height - TOWER_M, d2)
    azim = np.arctan2(xy[:, 1], xy[:, 0])
    ori = heading
    # Gudmundson shadowing along the path, Rician fading per sample.
    rho = np.exp(-SPEED_MPS * 0.1 / TRUE_DCORR_M)
    z = np.empty(n)
    z[0] = rng.standard_normal()
    for i in range(1, n):
        z[i] = rho * z[i - 1] + np.sqrt(1 - rho * rho) * rng.standard_normal()
    k = 10 ** (TRUE_K_DB / 10)
    g = np.abs(np.sqrt(k / (k + 1))
               + np.sqrt(0.5 / (k + 1)) * (rng.standard_normal(n) + 1j * rng.standard_normal(n))) ** 2
    pl_mean = TRUE_PL0_DB + 10 * TRUE_N[h] * np.log10(d3) + TRUE_SIGMA_DB[h] * z
    pl_true = pl_mean - 10 * np.log10(g)
    from uavcas.calibration.linkbudget import PatternGain
    from uavcas.calibration.loaders import RadiationPattern

    t = pattern_tables()
    pg = PatternGain(RadiationPattern(Path("synthetic"), t["theta2"], t["phi2"], t["G_t_dB"], t["G_r_dB"]))
    g_table = pg.gain_db(elev, azim, ori)
    g_real = g_table + TRUE_AIRFRAME_DB * np.cos(azim - ori)  # what the antennas really gave
    rsrp = TRUE_EIRP_DBM + g_real - pl_true
    pred_free = TRUE_EIRP_DBM + g_table - free_space_loss_db(d3, 3.51)
    return {
        "RSRP_s": rsrp, "RSRP_PL_free_s": pred_free, "RSRP_PL_two_s": pred_free, "dist_3D_s": d3,
        "dist_2D_new_s": d2, "height_s": height, "elev_s": elev, "azim_s": azim, "ori_s": ori,
        "sha_free_s": rsrp - pred_free, "_pl_true": pl_true, "_pl_mean": pl_mean,
        "_airframe_db": TRUE_AIRFRAME_DB * np.cos(azim - ori),
    }


def write_maeng(root: Path, n: int = 6000, seed: int = 0, fmt: str = "mat") -> dict[int, dict]:
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
            "power_all": k - pl, "RSRP_PL_free": k - free_space_loss_db(d3, 3.3), "dist_3D": d3, "dist_2D_new": d2,
            "h_all": height,
        })
