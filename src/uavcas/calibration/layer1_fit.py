"""Layer 1 fits on the training segments: log-distance with the effective antenna pattern,
two-ray, TR 36.777 UMa-AV, the shadowing spread and the Rician K factor.

Every fit sees only the training samples of `segments.contiguous_split`. Target per sample:
the antenna-compensated absolute path loss of `linkbudget.absolute_pathloss_db` (rad_pat.mat
gains at each sample's elevation, azimuth and UAV orientation).

Log-distance (the twin's `LogDistance`), fitted by least squares on the training local means
over `K_WINDOW_S` (1 s, 40 wavelengths: the fast fading averaged out, the shadowing kept; a
per-sample dB fit would sit E[10 log10 g] ~ 1 dB above the power-mean loss the twin's fading
layer expects):

    PL_lm = FSPL(1 m, fc) + dPL0 + 10 n(h) log10(d3D / 1 m) + c . f(angles),   dPL0 = 0

* carrier anchor: the close-in (CI) free-space reference model, dPL0 = 0 - the 1 m loss is
  free space at the carrier, so the model moves to another carrier by Friis and only n(h) is
  fitted (Sun et al., "Investigation of prediction accuracy, sensitivity, and parameter
  stability of large-scale propagation path loss models for 5G wireless communications", IEEE
  Trans. Veh. Technol. 65(5), 2016: CI is stable across frequencies and distance spans where a
  floating intercept is not). The distance span at one altitude is under one decade, so a
  fitted intercept trades slope for intercept (1 m excess +0.3..+5 dB between seeds here);
  ``logdistance_free`` reports the per-altitude-intercept fit beside it;
* per-altitude exponent n(h) and, from the residuals of the 5 s training local means (the
  twin's window, `LOCAL_MEAN_S`), per-altitude shadowing sigma(h);
* effective antenna pattern (in-flight pattern calibration, as Rahman et al. 2026, arXiv
  2603.10362, do on these flights): f = cos/sin of 1x and 2x the azimuth at the tower (its
  sector antenna and the ground around it) and cos/sin of the azimuth in the UAV body frame
  (the airframe around the receive antenna), one set of coefficients for all altitudes. The
  measured rad_pat.mat misses both: the residual swings +-4 dB with the tower azimuth
  identically at every altitude, and by 3 dB between the two headings of the survey lanes.
  The terms are centred on their training means, so the correction has zero mean over the
  training flights: it reshapes the pattern without moving its average gain (over the single
  120-degree sector these flights see, uncentred harmonics would also act as a constant and
  trade against the 1 m excess). These are antenna terms, not propagation: the twin's
  antennas are isotropic, so the correction is moved into the target (PL_eff = PL - c . f)
  for every model and reported as the effective gain error -c . f. ``logdistance_radpat`` is
  the fit without it.

K(h): Greenstein's moment method on the training samples in 1 s windows (`segments`).

Shadowing decorrelation distance (Gudmundson's exp(-d / d_corr), the twin's shadowing process):
the empirical semivariogram of the 1 s local-mean residuals along the flown path (pairs within
one training run), gamma(d) = nugget + s^2 (1 - exp(-d / d_corr)) fitted by least squares on
lags up to 200 m (the nugget absorbs the fading left in a 1 s mean; a variogram does not need
the residuals' mean, which biases short-run autocorrelations low); the median over the files.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.constants import c as SPEED_OF_LIGHT_M_S
from scipy.optimize import curve_fit, least_squares

from uavcas import seeding
from uavcas.channel import LinkGeometry, LogDistance, PathLossProfile, TwoRay, UMaAV, free_space_loss_db

from .linkbudget import MAENG_FC_GHZ, BudgetFit, PatternGain, absolute_pathloss_db, carrier_ghz
from .loaders import PathLossSamples
from .segments import (
    K_WINDOW_S,
    LOCAL_MEAN_S,
    SAMPLE_INTERVAL_S,
    SegmentSplit,
    contiguous_split,
    moment_k_db,
    power_mean_db,
    window_mean,
    window_size,
    windows,
)

FSPL_1M_DB = float(free_space_loss_db(1.0, MAENG_FC_GHZ))
_INTERCEPT = {"ci": "close-in: 1 m loss = free space", "shared": "one fitted 1 m excess over free space",
              "free": "fitted 1 m loss per altitude"}
PATTERN_TERMS = ("cos az_tower", "sin az_tower", "cos 2az_tower", "sin 2az_tower", "cos az_body", "sin az_body")


@dataclass
class Group:
    """One file prepared for fitting: geometry, targets and its split."""

    samples: PathLossSamples
    pl_db: np.ndarray  # antenna-compensated with rad_pat.mat (Maeng) or the file's budget (multi-band)
    split: SegmentSplit
    tx_height_m: float
    fc_ghz: float
    interval_s: float
    features: np.ndarray | None = None  # (n, len(PATTERN_TERMS)) or None (no angles)
    pl_eff_db: np.ndarray | None = None  # pl_db minus the fitted effective-pattern correction

    @property
    def altitude_m(self) -> float:
        return self.samples.altitude_m

    @property
    def train(self) -> np.ndarray:
        return self.split.train

    @property
    def test(self) -> np.ndarray:
        return self.split.test

    @property
    def target_db(self) -> np.ndarray:
        return self.pl_db if self.pl_eff_db is None else self.pl_eff_db

    def wins(self, mask: np.ndarray, span_s: float) -> list[np.ndarray]:
        return windows(mask, window_size(self.interval_s, span_s))


def pattern_features(s: PathLossSamples) -> np.ndarray | None:
    if s.elev_rad is None or s.azim_rad is None or s.ori_rad is None:
        return None
    az, body = s.azim_rad, s.azim_rad - s.ori_rad
    return np.c_[np.cos(az), np.sin(az), np.cos(2 * az), np.sin(2 * az), np.cos(body), np.sin(body)]


def prepare(samples: list[PathLossSamples], budgets: list[BudgetFit], pattern: PatternGain | None,
            seed: int | None) -> list[Group]:
    """Targets and splits; seed None = nothing held out (a cross-validation campaign)."""
    groups = []
    for s, b in zip(samples, budgets):
        interval = SAMPLE_INTERVAL_S.get(s.campaign, 0.1)
        if seed is None:
            split = SegmentSplit(train=np.zeros(len(s), bool), test=np.ones(len(s), bool), n_blocks=1, test_blocks=(0,))
        else:
            split = contiguous_split(len(s), interval, seed, int(s.altitude_m))
        groups.append(Group(s, absolute_pathloss_db(s, b, pattern), split, b.tx_height_m, carrier_ghz(s.campaign),
                            interval, pattern_features(s) if pattern is not None else None))
    return groups


# --------------------------------------------------------------------------------------------
# Log-distance with the effective antenna pattern
# --------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class LogDistanceFit:
    profile: PathLossProfile
    excess_1m_db: np.ndarray  # dPL0 per altitude (equal when shared)
    pattern_coef: np.ndarray | None  # c over PATTERN_TERMS (None: no pattern terms)
    pattern_centre: np.ndarray | None  # training means of the terms
    sigma_sample_db: tuple[float, ...]  # per-sample residual std on training (for reference)

    def correction_db(self, g: Group) -> np.ndarray:
        if self.pattern_coef is None or g.features is None:
            return np.zeros(len(g.samples))
        return (g.features - self.pattern_centre) @ self.pattern_coef


def fit_logdistance(groups: list[Group], intercept: str = "ci", pattern_terms: bool = True,
                    name: str = "calibrated") -> LogDistanceFit:
    """The fit of the module docstring on the training 1 s local means of `groups`; intercept
    "ci" (1 m loss = free space), "shared" (one fitted excess) or "free" (one per altitude)."""
    k = len(groups)
    n_int = {"ci": 0, "shared": 1, "free": k}[intercept]
    use_pat = pattern_terms and all(g.features is not None for g in groups)
    n_pat = len(PATTERN_TERMS) if use_pat else 0
    centre = np.concatenate([g.features[g.train] for g in groups]).mean(axis=0) if use_pat else None
    rows, ys = [], []
    for j, g in enumerate(groups):
        w = g.wins(g.train, K_WINDOW_S)
        y = power_mean_db(g.pl_db, w) - float(free_space_loss_db(1.0, g.fc_ghz))
        x = window_mean(10.0 * np.log10(np.maximum(g.samples.d3d_m, 1.0)), w)
        a = np.zeros((len(w), n_int + k + n_pat))
        if n_int:
            a[:, 0 if n_int == 1 else j] = 1.0
        off = n_int
        a[:, off + j] = x
        if use_pat:
            a[:, off + k:] = window_mean(g.features - centre, w)
        rows.append(a)
        ys.append(y)
    coef = np.linalg.lstsq(np.vstack(rows), np.concatenate(ys), rcond=None)[0]
    off = n_int
    excess = np.zeros(k) if n_int == 0 else np.full(k, coef[0]) if n_int == 1 else coef[:k]
    n = coef[off : off + k]
    pat = coef[off + k :] if use_pat else None
    fspl = np.array([float(free_space_loss_db(1.0, MAENG_FC_GHZ))] * k)
    prof = PathLossProfile(
        name=name,
        source=f"uavcas calibrate: Maeng LTE 3.51 GHz, {_INTERCEPT[intercept]}, "
        f"{'effective antenna pattern, ' if use_pat else ''}training segments; sigma from 5 s local means; altitudes = "
        f"median UAV height of the {', '.join(f'{g.altitude_m:g}' for g in groups)} m files",
        fc_ghz=MAENG_FC_GHZ,
        altitude_m=tuple(float(np.median(g.samples.height_m)) for g in groups),
        n=tuple(float(v) for v in n),
        pl0_db=tuple(float(v) for v in fspl + excess),
        sigma_db=(0.0,) * k,
    )
    fit = LogDistanceFit(prof, excess, pat, centre, ())
    sig, sig_s = [], []
    for i, g in enumerate(groups):
        target = g.pl_db - fit.correction_db(g)
        pred = logdist_loss_db(prof, g, slice(None), i)
        w = g.wins(g.train, LOCAL_MEAN_S)
        sig.append(float(np.std(power_mean_db(target, w) - power_mean_db(pred, w), ddof=1)))
        sig_s.append(float(np.std((target - pred)[g.train], ddof=1)))
    return LogDistanceFit(prof.model_copy(update={"sigma_db": tuple(sig)}), excess, pat, centre, tuple(sig_s))


def logdist_loss_db(profile: PathLossProfile, g: Group, mask=slice(None),
                    at_profile_altitude: int | None = None) -> np.ndarray:
    """The twin's LogDistance at the group's carrier; at the group's own profile altitude (a
    calibration file) or at the measured heights (another campaign: the twin interpolates)."""
    s = g.samples
    h = profile.altitude_m[at_profile_altitude] if at_profile_altitude is not None else s.height_m[mask]
    return LogDistance(profile, g.fc_ghz).loss_at_db(s.d3d_m[mask], h)


def fit_decorrelation_m(groups: list[Group], fit: LogDistanceFit, max_lag_m: float = 200.0) -> float:
    """Median over files of the fitted Gudmundson decorrelation distance (module docstring)."""
    out = []
    for i, g in enumerate(groups):
        s = g.samples
        if s.azim_rad is None:
            continue
        w = g.wins(g.train, K_WINDOW_S)
        if len(w) < 10:
            continue
        resid = (power_mean_db(g.pl_db - fit.correction_db(g), w)
                 - power_mean_db(logdist_loss_db(fit.profile, g, slice(None), i), w))
        xy = window_mean(np.c_[s.d2d_m * np.cos(s.azim_rad), s.d2d_m * np.sin(s.azim_rad)], w)
        joined = np.array([w[j + 1][0] == w[j][-1] + 1 for j in range(len(w) - 1)], dtype=bool)
        run_id = np.r_[0, np.cumsum(~joined)]  # windows of one contiguous training run share an id
        step = np.linalg.norm(np.diff(xy, axis=0), axis=1)[joined] if joined.any() else np.zeros(0)
        med = float(np.median(step)) if step.size else 0.0
        if med <= 0:
            continue
        lags, gam = [], []
        for lag in range(1, int(max_lag_m / med) + 1):
            same = run_id[lag:] == run_id[:-lag]
            if same.sum() < 20:
                break
            lags.append(lag * med)
            gam.append(0.5 * float(np.mean((resid[lag:][same] - resid[:-lag][same]) ** 2)))
        if len(lags) < 5:
            continue

        def model(d, nugget, sill, dc):
            return nugget + sill * (1.0 - np.exp(-d / dc))

        try:
            p, _ = curve_fit(model, np.array(lags), np.array(gam), p0=[gam[0] / 2, max(gam), 50.0],
                             bounds=([0.0, 0.0, 1.0], [np.inf, np.inf, 1000.0]))
            out.append(float(p[2]))
        except RuntimeError:
            continue
    return float(np.median(out)) if out else float("nan")


def fit_k_db(g: Group) -> float:
    """Rician K (dB) of a file's training samples (`segments.moment_k_db`, 1 s windows)."""
    return moment_k_db(-g.pl_db, g.wins(g.train, K_WINDOW_S))


# --------------------------------------------------------------------------------------------
# Two-ray and UMa-AV
# --------------------------------------------------------------------------------------------


def two_ray_pattern_loss_db(model: TwoRay, d2d_m, h_tx_m, h_rx_m, amplitude_ratio=1.0) -> np.ndarray:
    """The twin's `TwoRay.loss_at_db` with the reflected ray scaled by the antennas' amplitude
    ratio; identical to it for a ratio of 1 (tested). Fresnel coefficient from the twin's model."""
    lam = SPEED_OF_LIGHT_M_S / (model.fc_ghz * 1e9)
    d2 = np.asarray(d2d_m, dtype=float)
    ht, hr = np.asarray(h_tx_m, dtype=float), np.asarray(h_rx_m, dtype=float)
    r1 = np.maximum(np.hypot(d2, ht - hr), 1.0)
    r2 = np.hypot(d2, ht + hr)
    gamma = model.reflection_coefficient((ht + hr) / r2) * amplitude_ratio
    field = 1.0 / r1 + gamma * np.exp(-1j * 2.0 * np.pi / lam * (r2 - r1)) / r2
    return -20.0 * np.log10(lam / (4.0 * np.pi) * np.maximum(np.abs(field), 1e-12))


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
        psi = np.arctan2(s.height_m[mask] + g.tx_height_m, s.d2d_m[mask])
        g_dir = self.pattern.gain_db(s.elev_rad[mask], s.azim_rad[mask], s.ori_rad[mask])
        g_ref = self.pattern.gain_db(-psi, s.azim_rad[mask], s.ori_rad[mask])
        return 10.0 ** ((g_ref - g_dir) / 20.0)

    def as_dict(self) -> dict:
        return {"eps_r": self.model.eps_r, "conductivity_s_m": self.model.conductivity_s_m,
                "polarisation": self.model.polarisation, "offset_db": self.offset_db,
                "reflected_ray_pattern": self.pattern is not None}


def fit_two_ray(groups: list[Group], pattern: PatternGain | None = None, max_samples: int = 20000,
                seed: int = 0) -> TwoRayFit:
    """Vertical polarisation (the AERPAW antennas are vertical; a free polarisation lets the fit
    pick horizontal with eps_r -> 1, i.e. a ground that reflects nothing). Ground eps_r in
    [2, 80] (dry sand to water, ITU-R P.527), conductivity in [1e-5, 1] S/m, offset +-30 dB;
    soft-L1 loss on training samples (the model's nulls are deeper than any measurement)."""
    idx = [np.flatnonzero(g.train) for g in groups]
    per = max(1, max_samples // len(groups))
    rng = seeding.generator(seed)
    idx = [np.sort(rng.choice(i, size=min(per, i.size), replace=False)) for i in idx]  # keeps the fit fast

    def make(p) -> TwoRayFit:
        return TwoRayFit(TwoRay(eps_r=float(p[0]), conductivity_s_m=float(10 ** p[1]), polarisation="vertical"),
                         float(p[2]), pattern)

    def resid(p):
        fit = make(p)
        return np.concatenate([fit.predict(g, i) - g.target_db[i] for g, i in zip(groups, idx)])

    sol = least_squares(resid, x0=[15.0, -3.0, 0.0], bounds=([2.0, -5.0, -30.0], [80.0, 0.0, 30.0]), loss="soft_l1",
                        f_scale=5.0)
    return make(sol.x)


def uma_loss_db(g: Group, mask=slice(None)) -> np.ndarray:
    """TR 36.777 UMa-AV as specified (LOS-probability-weighted mean), BS at the tower height."""
    s = g.samples
    d3 = s.d3d_m[mask]
    geom = LinkGeometry(d3d_m=d3, d2d_m=s.d2d_m[mask], h_ground_m=np.full(d3.shape, g.tx_height_m),
                        h_air_m=s.height_m[mask], air_to_air=np.zeros(d3.shape, bool))
    return UMaAV(fc_ghz=g.fc_ghz, h_bs_m=g.tx_height_m).evaluate(geom, None).loss_db
