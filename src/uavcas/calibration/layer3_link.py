"""Layer 3: replay real AFAR trajectories through the twin's channel chain, compare with the
measured channel power.

Geometry: the rover (the transmitter, 1.5 m antenna) is the ground end at the origin; the UAV's
track in east/north/up metres about it (layer 2's mission phase, `TraceMission` replay, 1 s
step). Measured power is averaged per 1 s step in linear units (mW) and converted back to dB,
so both series live on the same time grid.

Chain: the twin's `Channel` (2 nodes: rover as BS, UAV), evaluated once per step in time order
so Gudmundson shadowing (layer 1's decorrelation distance) and the LOS state evolve with the
UAV's displacement, exactly as in a plan, with layer 1's Rician K(h) in its link layer. Budget: TX_DBM = 20 dBm, 0 dBi,
noise -95 dBm (the twin's defaults); simulated RSS = TX_DBM - total path loss. Variants: the calibrated log-distance
profile (layer 1; the built-in paper-anchored profile when layer 1 did not run) and TR 36.777 UMa-AV.

Scale: the sounder's power is uncalibrated (dB re an unknown reference), so one constant offset
maps it to dBm: offset = median(sim_median - measured) over TRAINING flights only (a seeded 70 %
of the flights); held-out flights are scored with it. Reported on held-out flights: median
absolute error of the offset-corrected power against the chain (with shadowing, as the twin
runs it) and against the median loss (no shadowing), per 10 m altitude bin, and the Pearson r
of the RSS time series per flight (SNR = RSS + 95 dB here, so its r is the same number).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.stats import pearsonr

from uavcas.channel import Channel, KFactorProfile, PathLossProfile
from uavcas.mobility import TraceMission

from .layer2_mobility import STEP_S, cruise_slice, flight_xyz_m, split_flights
from .loaders import AfarFlight, CalibrationDataError

TX_DBM = 20.0
NOISE_DBM = -95.0
ALT_BIN_M = 10.0
VARIANTS = ("logdistance", "uma_av")


@dataclass
class Replay:
    """One flight on the 1 s grid: measured power and the simulated chain."""

    name: str
    t_s: np.ndarray
    alt_m: np.ndarray
    d3d_m: np.ndarray
    measured_db: np.ndarray  # sounder scale
    rss_chain_dbm: dict  # variant -> RSS with shadowing
    rss_median_dbm: dict  # variant -> RSS without shadowing
    snr_chain_db: dict
    rate_mbps: dict


def measured_per_step(f: AfarFlight, sl: slice, t0: float, n: int) -> np.ndarray:
    k = np.floor((f.t_s[sl] - t0) / STEP_S).astype(np.int64)
    ok = (k >= 0) & (k < n)
    mw = np.bincount(k[ok], weights=10.0 ** (f.power_db[sl][ok] / 10.0), minlength=n)
    cnt = np.bincount(k[ok], minlength=n)
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(cnt > 0, 10.0 * np.log10(mw / np.maximum(cnt, 1)), np.nan)


def replay_flight(f: AfarFlight, profile: PathLossProfile | None, seed: int, fc_ghz: float = 3.51,
                  fading: KFactorProfile | None = None, d_corr_m: float = 50.0) -> Replay:
    xyz = flight_xyz_m(f)
    sl = cruise_slice(xyz[:, 2])
    t_raw, p_raw = f.t_s[sl], xyz[sl]
    trace = TraceMission(t_raw, p_raw)  # the twin's replay of a recorded track
    t = np.arange(0.0, trace.duration_s, STEP_S)
    # The step k covers [t_k, t_k + STEP_S): position at its middle, power averaged over it.
    pos = trace.positions(np.minimum(t + STEP_S / 2, trace.duration_s))[:, 0, :]
    meas = measured_per_step(f, sl, t_raw[0], len(t))
    rover = np.array([0.0, 0.0, f.rover_height_m])
    out: dict = {"chain": {}, "median": {}, "snr": {}, "rate": {}}
    for variant in VARIANTS:
        ch = Channel(n_nodes=2, pathloss="logdist" if variant == "logdistance" else "uma", profile=profile,
                     seed=seed, tx_power_dbm=TX_DBM, noise_dbm=NOISE_DBM, fc_ghz=fc_ghz, fading=fading,
                     d_corr_m=d_corr_m)
        total, shadow, snr, rate = (np.empty(len(t)) for _ in range(4))
        pairs, is_bs = np.array([[0, 1]]), np.array([True, False])
        for k in range(len(t)):
            la = ch.evaluate(np.vstack([rover, pos[k]]), pairs, is_bs)
            total[k], shadow[k], snr[k], rate[k] = la.pathloss_db[0], la.shadow_db[0], la.snr_db[0], la.rate_mbps[0]
        out["chain"][variant] = TX_DBM - total
        out["median"][variant] = TX_DBM - (total - shadow)
        out["snr"][variant] = snr
        out["rate"][variant] = rate
    ok = np.isfinite(meas)
    d3 = np.linalg.norm(pos - rover, axis=1)
    return Replay(f.name, t[ok], pos[ok, 2], d3[ok], meas[ok], {k: v[ok] for k, v in out["chain"].items()},
                  {k: v[ok] for k, v in out["median"].items()}, {k: v[ok] for k, v in out["snr"].items()},
                  {k: v[ok] for k, v in out["rate"].items()})


@dataclass
class Layer3Result:
    replays: list[Replay]
    train: list[str]
    test: list[str]
    offset_db: dict  # variant -> sounder-to-dBm offset (training flights)
    results: dict
    representative: str


def _r(a, b) -> float:
    return float(pearsonr(a, b)[0]) if len(a) > 2 and np.std(a) > 0 and np.std(b) > 0 else float("nan")


def run_layer3(flights: list[AfarFlight], profile: PathLossProfile | None, seed: int = 0,
               fading: KFactorProfile | None = None, d_corr_m: float = 50.0) -> Layer3Result:
    usable = [f for f in flights if f.rover_lon_lat is not None]
    if len(usable) < 2:
        raise CalibrationDataError(
            "layer 3 needs >= 2 AFAR flights with a processed file (results_useful_with_tworay_tilt_src_exp_*) to "
            "locate the rover"
        )
    replays = [replay_flight(f, profile, seed + i, fading=fading, d_corr_m=d_corr_m) for i, f in enumerate(usable)]
    tr_i, te_i = split_flights([r.name for r in replays], seed, 99)
    train, test = [replays[i] for i in tr_i], [replays[i] for i in te_i]
    offsets, results = {}, {}
    for v in VARIANTS:
        off = float(np.median(np.concatenate([r.rss_median_dbm[v] - r.measured_db for r in train])))
        offsets[v] = off
        meas = np.concatenate([r.measured_db + off for r in test])
        chain = np.concatenate([r.rss_chain_dbm[v] for r in test])
        med = np.concatenate([r.rss_median_dbm[v] for r in test])
        raw = np.concatenate([r.measured_db for r in test])
        alt = np.concatenate([r.alt_m for r in test])
        bins = {}
        for lo in np.arange(np.floor(alt.min() / ALT_BIN_M) * ALT_BIN_M, alt.max(), ALT_BIN_M):
            m = (alt >= lo) & (alt < lo + ALT_BIN_M)
            if m.sum() >= 10:
                bins[f"{lo:g}-{lo + ALT_BIN_M:g} m"] = {
                    "n": int(m.sum()),
                    "median_ae_db": float(np.median(np.abs(chain[m] - meas[m]))),
                    "median_ae_no_shadow_db": float(np.median(np.abs(med[m] - meas[m]))),
                }
        per_flight = {r.name: {"r_chain": _r(r.rss_chain_dbm[v], r.measured_db),
                               "r_median": _r(r.rss_median_dbm[v], r.measured_db),
                               "n": int(len(r.t_s))} for r in test}
        results[v] = {
            "offset_db": off,
            "median_ae_db": float(np.median(np.abs(chain - meas))),
            "median_ae_no_shadow_db": float(np.median(np.abs(med - meas))),
            "median_ae_uncorrected_db": float(np.median(np.abs(chain - raw))),
            "bias_db": float(np.mean(chain - meas)),
            "pearson_r_median_over_flights": float(np.nanmedian([p["r_chain"] for p in per_flight.values()])),
            "pearson_r_no_shadow_median_over_flights": float(np.nanmedian([p["r_median"]
                                                                           for p in per_flight.values()])),
            "pearson_r_pooled": _r(chain, meas),
            "per_altitude": bins,
            "per_flight": per_flight,
            "n_samples": int(len(meas)),
        }
    rs = {name: p["r_chain"] for name, p in results["logdistance"]["per_flight"].items()}
    order = sorted(rs, key=lambda k: rs[k])
    rep = order[len(order) // 2] if order else replays[0].name
    return Layer3Result(replays, [r.name for r in train], [r.name for r in test], offsets, results, rep)


def layer3_json(res: Layer3Result) -> dict:
    return {
        "budget": {"tx_dbm": TX_DBM, "gains_dbi": 0.0, "noise_dbm": NOISE_DBM, "step_s": STEP_S},
        "offset": "median(sim_median - measured) on training flights; sounder dB + offset = dBm",
        "train_flights": res.train,
        "test_flights": res.test,
        "representative_flight": res.representative,
        "variants": res.results,
    }
