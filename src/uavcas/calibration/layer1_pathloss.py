"""Layer 1: altitude-dependent path loss fitted to Maeng LTE, cross-validated on the multi-band set.

Target: absolute, antenna-compensated path loss from `linkbudget.absolute_pathloss_db`.
Split: per altitude, a seeded 70/30 permutation of the samples (SeedSequence([seed, h])). The
samples are a flight's time series, so neighbouring samples are correlated and the held-out
score is optimistic; the multi-band campaign (other hardware, waveform, day) is the honest test.
Nothing is ever fitted on the multi-band data.

Models, each evaluated with the twin's own code (`uavcas.channel`):
* ``logdistance``: PL = PL0 + 10 n(h) log10(d3D / 1 m), the twin's `LogDistance`. Least squares
  (numpy lstsq) on the training split. `intercept="shared"` (default) fits ONE PL0 for all
  altitudes with a slope per altitude: the distance span at one altitude is under one decade
  (94-499 m at 110 m), so a per-altitude intercept is an extrapolation to 1 m that trades slope
  for intercept (it gives 27 dB at 110 m, 16 dB below free space); pooling the five altitudes
  (27-499 m) pins the 1 m loss, while n(h) and sigma(h) stay per altitude. The per-altitude-
  intercept fit is reported too (``logdistance_free``). sigma(h) = residual std (ddof 2).
  Profile altitudes are each file's median measured UAV height (the twin interpolates in the
  height it flies); the campaign's nominal labels are kept alongside.
* ``two_ray``: coherent ground reflection between the tower and UAV heights with the twin's
  `TwoRay` Fresnel coefficient, the reflected ray weighted by the measured pattern (its
  departure/arrival angle -psi vs the direct ray's elevation; `two_ray_pattern_loss_db`, equal
  to `TwoRay.loss_db` when the weight is 1 - the multi-band files, whose antenna is another),
  plus one constant excess loss. Ground permittivity, log-conductivity and the offset fitted with
  scipy least_squares (soft-L1: the model's interference nulls are deeper than any averaged
  measurement) on the pooled training split. The twin's profile has no two-ray parameters, so
  this fit is reported, not written to the profile.
* ``uma_av``: the twin's TR 36.777 `UMaAV` (LOS-probability-weighted mean loss, h_BS = the tower
  height) as specified, no fit; ``uma_av_offset`` adds one constant fitted on training data.

Carrier: predictions at another campaign's carrier use each model's own fc (two-ray, UMa-AV);
the log-distance fit is moved by Friis' 20 log10(fc / 3.51 GHz).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.constants import c as SPEED_OF_LIGHT_M_S
from scipy.optimize import least_squares

from uavcas.channel import LinkGeometry, LogDistance, PathLossProfile, TwoRay, UMaAV, free_space_loss_db

from .linkbudget import MAENG_FC_GHZ, BudgetFit, PatternGain, absolute_pathloss_db, carrier_ghz, recover_budget
from .loaders import PathLossSamples, RadiationPattern
from .metrics import error_metrics

MODELS = ("logdistance", "logdistance_free", "two_ray", "uma_av", "uma_av_offset")
FSPL_1M_DB = float(free_space_loss_db(1.0, MAENG_FC_GHZ))


@dataclass
class Group:
    """One file's samples prepared for fitting: geometry, target PL, and its train mask."""

    samples: PathLossSamples
    pl_db: np.ndarray
    train: np.ndarray  # bool
    tx_height_m: float
    fc_ghz: float

    @property
    def altitude_m(self) -> float:
        return self.samples.altitude_m


def split_mask(n: int, seed: int, key: int, train_frac: float = 0.7) -> np.ndarray:
    rng = np.random.default_rng(np.random.SeedSequence([seed, key]))
    mask = np.zeros(n, dtype=bool)
    mask[rng.permutation(n)[: int(round(train_frac * n))]] = True
    return mask


def prepare(samples: list[PathLossSamples], budgets: list[BudgetFit], seed: int | None) -> list[Group]:
    groups = []
    for s, b in zip(samples, budgets):
        train = split_mask(len(s), seed, int(s.altitude_m)) if seed is not None else np.zeros(len(s), bool)
        groups.append(Group(s, absolute_pathloss_db(s), train, b.tx_height_m, carrier_ghz(s.campaign)))
    return groups


# --------------------------------------------------------------------------------------------
# Fits
# --------------------------------------------------------------------------------------------


def fit_logdistance(groups: list[Group], shared_intercept: bool = True) -> PathLossProfile:
    """n(h), PL0(h), sigma(h) on the training samples of each group (d0 = 1 m)."""
    k = len(groups)
    logs = [10.0 * np.log10(np.maximum(g.samples.d3d_m[g.train], 1.0)) for g in groups]
    ys = [g.pl_db[g.train] for g in groups]
    if shared_intercept:
        rows = sum(len(y) for y in ys)
        a = np.zeros((rows, 1 + k))
        a[:, 0] = 1.0
        i = 0
        for j, x in enumerate(logs):
            a[i : i + len(x), 1 + j] = x
            i += len(x)
        coef = np.linalg.lstsq(a, np.concatenate(ys), rcond=None)[0]
        pl0, n = np.full(k, coef[0]), coef[1:]
    else:
        fits = [np.linalg.lstsq(np.c_[np.ones_like(x), x], y, rcond=None)[0] for x, y in zip(logs, ys)]
        pl0, n = np.array([f[0] for f in fits]), np.array([f[1] for f in fits])
    sigma = np.array([np.std(y - (p + m * x), ddof=2) for x, y, p, m in zip(logs, ys, pl0, n)])
    heights = np.array([float(np.median(g.samples.height_m)) for g in groups])
    return PathLossProfile(
        name="calibrated",
        source=f"uavcas calibrate pathloss: Maeng LTE 3.51 GHz, {'shared' if shared_intercept else 'per-altitude'} "
        f"intercept, 70/30 split; altitudes = median UAV height of the {', '.join(f'{g.altitude_m:g}' for g in groups)} m files",
        fc_ghz=MAENG_FC_GHZ,
        altitude_m=tuple(float(h) for h in heights),
        n=tuple(float(v) for v in n),
        pl0_db=tuple(float(v) for v in pl0),
        sigma_db=tuple(float(v) for v in sigma),
    )


@dataclass(frozen=True)
class TwoRayFit:
    model: TwoRay
    offset_db: float
    pattern: PatternGain | None = None

    def predict(self, g: Group, mask=slice(None)) -> np.ndarray:
        s = g.samples
        m = TwoRay(fc_ghz=g.fc_ghz, eps_r=self.model.eps_r, conductivity_s_m=self.model.conductivity_s_m,
                   polarisation=self.model.polarisation)
        return two_ray_pattern_loss_db(m, s.d2d_m[mask], g.tx_height_m, s.height_m[mask],
                                       self._amplitude_ratio(g, mask)) + self.offset_db

    def _amplitude_ratio(self, g: Group, mask) -> np.ndarray | float:
        """sqrt(G_reflected / G_direct): the reflected ray leaves the tower and reaches the UAV
        at the grazing angle -psi below the horizon, the direct ray at the elevation; the
        target PL is compensated for the direct ray's gain only. 1 where there are no angles."""
        s = g.samples
        if self.pattern is None or s.elev_rad is None or s.azim_rad is None or s.ori_rad is None:
            return 1.0
        h_sum = s.height_m[mask] + g.tx_height_m
        psi = np.arctan2(h_sum, s.d2d_m[mask])
        g_dir = self.pattern.gain_db(s.elev_rad[mask], s.azim_rad[mask], s.ori_rad[mask])
        g_ref = self.pattern.gain_db(-psi, s.azim_rad[mask], s.ori_rad[mask])
        return 10.0 ** ((g_ref - g_dir) / 20.0)

    def as_dict(self) -> dict:
        return {"eps_r": self.model.eps_r, "conductivity_s_m": self.model.conductivity_s_m,
                "polarisation": self.model.polarisation, "offset_db": self.offset_db,
                "reflected_ray_pattern": self.pattern is not None}


def two_ray_pattern_loss_db(model: TwoRay, d2d_m, h_tx_m, h_rx_m, amplitude_ratio=1.0) -> np.ndarray:
    """The twin's `TwoRay.loss_db` with the reflected ray scaled by the antennas' amplitude
    ratio; identical to it for a ratio of 1 (tested). Fresnel coefficient from the twin's model."""
    lam = SPEED_OF_LIGHT_M_S / (model.fc_ghz * 1e9)
    d2 = np.asarray(d2d_m, dtype=float)
    ht, hr = np.asarray(h_tx_m, dtype=float), np.asarray(h_rx_m, dtype=float)
    r1 = np.maximum(np.hypot(d2, ht - hr), 1.0)
    r2 = np.hypot(d2, ht + hr)
    gamma = model.reflection_coefficient((ht + hr) / r2) * amplitude_ratio
    field = 1.0 / r1 + gamma * np.exp(-1j * 2.0 * np.pi / lam * (r2 - r1)) / r2
    return -20.0 * np.log10(lam / (4.0 * np.pi) * np.maximum(np.abs(field), 1e-12))


def fit_two_ray(groups: list[Group], pattern: PatternGain | None = None, max_samples: int = 20000, seed: int = 0) -> TwoRayFit:
    """Vertical polarisation (the AERPAW antennas are vertical; a free polarisation lets the fit
    pick horizontal with eps_r -> 1, i.e. a ground that reflects nothing). Ground eps_r in
    [2, 80] (dry sand to water, ITU-R P.527), conductivity in [1e-5, 1] S/m, offset +-30 dB."""
    idx = [np.flatnonzero(g.train) for g in groups]
    per = max(1, max_samples // len(groups))
    rng = np.random.default_rng(seed)
    idx = [rng.choice(i, size=min(per, i.size), replace=False) for i in idx]  # keeps the fit fast

    def make(p) -> TwoRayFit:
        return TwoRayFit(TwoRay(eps_r=float(p[0]), conductivity_s_m=float(10 ** p[1]), polarisation="vertical"), float(p[2]), pattern)

    def resid(p):
        fit = make(p)
        return np.concatenate([fit.predict(g, i) - g.pl_db[i] for g, i in zip(groups, idx)])

    sol = least_squares(resid, x0=[15.0, -3.0, 0.0], bounds=([2.0, -5.0, -30.0], [80.0, 0.0, 30.0]), loss="soft_l1", f_scale=5.0)
    return make(sol.x)


def uma_loss_db(g: Group, mask=slice(None)) -> np.ndarray:
    s = g.samples
    model = UMaAV(fc_ghz=g.fc_ghz, h_bs_m=g.tx_height_m)
    geom = LinkGeometry(d3d_m=s.d3d_m[mask], d2d_m=s.d2d_m[mask], h_ground_m=np.full(s.d3d_m[mask].shape, g.tx_height_m),
                        h_air_m=s.height_m[mask], air_to_air=np.zeros(s.d3d_m[mask].shape, bool))
    return model.evaluate(geom, None).loss_db


def logdist_loss_db(profile: PathLossProfile, g: Group, mask=slice(None), at_profile_altitude: int | None = None) -> np.ndarray:
    """The twin's LogDistance; at the group's own profile altitude (Maeng) or at the measured
    heights (another campaign: the twin interpolates), Friis-shifted to the group's carrier."""
    s = g.samples
    h = profile.altitude_m[at_profile_altitude] if at_profile_altitude is not None else s.height_m[mask]
    return LogDistance(profile).loss_db(s.d3d_m[mask], h) + 20.0 * np.log10(g.fc_ghz / profile.fc_ghz)


# --------------------------------------------------------------------------------------------
# Whole layer
# --------------------------------------------------------------------------------------------


@dataclass
class Layer1Result:
    budgets: list[BudgetFit]
    crossval_budgets: list[BudgetFit]
    profile: PathLossProfile
    profile_free: PathLossProfile
    two_ray: TwoRayFit
    uma_offset_db: float
    models: dict  # model -> {"heldout": metrics, "crossval": metrics, "per_altitude": {...}}
    groups: list[Group]
    crossval_groups: list[Group]
    predictions: dict  # (model, "heldout"|"crossval", i) -> array (for figures)

    @property
    def pl_at_1m_db(self) -> float:
        return float(self.profile.pl0_db[0]) if len(set(self.profile.pl0_db)) == 1 else float(np.median(self.profile.pl0_db))


def run_layer1(maeng: list[PathLossSamples], multibw: list[PathLossSamples], pattern: RadiationPattern | None,
               seed: int = 0) -> Layer1Result:
    pg = PatternGain(pattern) if pattern is not None else None
    budgets = [recover_budget(s, pg) for s in maeng]
    cv_budgets = [recover_budget(s, None) for s in multibw]
    groups = prepare(maeng, budgets, seed)
    cv = prepare(multibw, cv_budgets, None)
    profile = fit_logdistance(groups, shared_intercept=True)
    profile_free = fit_logdistance(groups, shared_intercept=False)
    two_ray = fit_two_ray(groups, pg, seed=seed)
    uma_train = np.concatenate([uma_loss_db(g, g.train) - g.pl_db[g.train] for g in groups])
    uma_offset = -float(np.mean(uma_train))

    def predict(model: str, g: Group, i: int | None, mask) -> np.ndarray:
        if model == "logdistance":
            return logdist_loss_db(profile, g, mask, i)
        if model == "logdistance_free":
            return logdist_loss_db(profile_free, g, mask, i)
        if model == "two_ray":
            return two_ray.predict(g, mask)
        if model == "uma_av":
            return uma_loss_db(g, mask)
        return uma_loss_db(g, mask) + uma_offset

    models: dict = {}
    preds: dict = {}
    for model in MODELS:
        per_alt, all_p, all_m = {}, [], []
        for i, g in enumerate(groups):
            test = ~g.train
            p = predict(model, g, i, test)
            preds[(model, "heldout", i)] = p
            per_alt[f"{g.altitude_m:g}"] = error_metrics(p, g.pl_db[test])
            all_p.append(p)
            all_m.append(g.pl_db[test])
        cv_alt: dict = {}
        cv_p, cv_m = [], []
        for j, g in enumerate(cv):
            p = predict(model, g, None, slice(None))
            preds[(model, "crossval", j)] = p
            key = f"{g.altitude_m:g}"
            cv_alt.setdefault(key, ([], []))
            cv_alt[key][0].append(p)
            cv_alt[key][1].append(g.pl_db)
            cv_p.append(p)
            cv_m.append(g.pl_db)
        models[model] = {
            "heldout": error_metrics(np.concatenate(all_p), np.concatenate(all_m)),
            "crossval": error_metrics(np.concatenate(cv_p), np.concatenate(cv_m)) if cv_p else None,
            "per_altitude": per_alt,
            "crossval_per_altitude": {k: error_metrics(np.concatenate(a), np.concatenate(b)) for k, (a, b) in cv_alt.items()},
        }
    return Layer1Result(budgets, cv_budgets, profile, profile_free, two_ray, uma_offset, models, groups, cv, preds)


def layer1_json(res: Layer1Result) -> dict:
    prof = res.profile
    return {
        "target": "absolute antenna-compensated path loss PL = EIRP_eff + G_pattern - P_rx (dB); see linkbudget.py",
        "split": "seeded 70/30 per altitude (Maeng); cross-validation on the multi-band campaign, nothing fitted on it",
        "error_convention": "e = predicted - measured; bias_db = mean e",
        "fspl_1m_db": FSPL_1M_DB,
        "pl_at_1m_db": res.pl_at_1m_db,
        "pl_at_1m_minus_fspl_db": res.pl_at_1m_db - FSPL_1M_DB,
        "link_budget": {"maeng": [b.as_dict() for b in res.budgets], "multibw": [b.as_dict() for b in res.crossval_budgets]},
        "logdistance_params": {
            "nominal_altitude_m": [g.altitude_m for g in res.groups],
            "altitude_m": list(prof.altitude_m), "n": list(prof.n), "pl0_db": list(prof.pl0_db), "sigma_db": list(prof.sigma_db),
            "n_train": [int(g.train.sum()) for g in res.groups], "n_test": [int((~g.train).sum()) for g in res.groups],
        },
        "logdistance_free_params": {"n": list(res.profile_free.n), "pl0_db": list(res.profile_free.pl0_db),
                                    "sigma_db": list(res.profile_free.sigma_db)},
        "two_ray_params": res.two_ray.as_dict(),
        "uma_av_offset_db": res.uma_offset_db,
        "crossval_files": [g.samples.label for g in res.crossval_groups],
        "models": res.models,
        "checks": {
            "pl_at_1m_within_10db_of_free_space": abs(res.pl_at_1m_db - FSPL_1M_DB) <= 10.0,
            "logdistance_beats_uma_av_heldout": res.models["logdistance"]["heldout"]["rmse_db"] < res.models["uma_av"]["heldout"]["rmse_db"],
        },
    }
