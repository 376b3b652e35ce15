"""Layer 1: path loss fitted to Maeng LTE on training segments, scored on held-out segments and
on the multi-band campaign (nothing fitted on it).

Fits: `layer1_fit` (log-distance with the carrier anchor and the effective antenna pattern,
sigma(h), K(h), two-ray, UMa-AV). Split: `segments.contiguous_split` (60 s blocks, 30 % held
out per file, 5 s guards). Scores (e = predicted - measured, `metrics.error_metrics`), for
each model, on two scales of the same held-out samples:

* ``heldout_sample``: every held-out sample. Bounded below by what the samples allow
  (`layer1_ceiling`, reported beside it: the spread about the 5 s local mean, the
  least-squares optimum of log-distance on all samples, boosted trees on the geometry).
* ``heldout_local_mean``: 5 s local means (the twin's window; `segments.power_mean_db`) of the
  measured and the predicted loss - the quantity the twin's path loss stands for.

Cross-validation (``crossval_sample``, ``crossval_local_mean``): the multi-band campaign at
3.3 GHz (its own antennas and hardware; target from each file's own budget term), predicted at
its carrier (the log-distance profile through its carrier anchor) and measured heights. The
effective-pattern correction is the Maeng hardware's and is not applied there.

Models: logdistance (the twin's, with everything above), logdistance_free (per-altitude 1 m
intercepts), logdistance_radpat (rad_pat.mat only, no effective-pattern terms), two_ray (fitted
ground and offset), uma_av (TR 36.777 as specified, BS at the recovered tower height),
uma_av_offset (plus one constant fitted on training).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from uavcas.channel import KFactorProfile, PathLossProfile

from .layer1_ceiling import layer1_ceiling
from .layer1_fit import (
    FSPL_1M_DB,
    PATTERN_TERMS,
    Group,
    LogDistanceFit,
    TwoRayFit,
    fit_decorrelation_m,
    fit_k_db,
    fit_logdistance,
    fit_two_ray,
    logdist_loss_db,
    prepare,
    uma_loss_db,
)
from .linkbudget import BudgetFit, PatternGain, recover_budget
from .loaders import PathLossSamples, RadiationPattern
from .metrics import error_metrics
from .segments import BLOCK_S, GUARD_S, LOCAL_MEAN_S, TEST_FRACTION, power_mean_db

MODELS = ("logdistance", "logdistance_free", "logdistance_radpat", "two_ray", "uma_av", "uma_av_offset")
SCALES = ("sample", "local_mean")

__all__ = ["FSPL_1M_DB", "MODELS", "Layer1Result", "layer1_json", "run_layer1"]


@dataclass
class Layer1Result:
    budgets: list[BudgetFit]
    crossval_budgets: list[BudgetFit]
    fit: LogDistanceFit
    fit_free: LogDistanceFit
    fit_radpat: LogDistanceFit
    k_factor: KFactorProfile
    decorrelation_m: float
    two_ray: TwoRayFit
    uma_offset_db: float
    models: dict  # model -> {"heldout_sample": metrics, ..., "per_altitude": {...}}
    groups: list[Group]
    crossval_groups: list[Group]
    predictions: dict  # (model, "heldout"|"crossval", i) -> per-sample array over the scored samples
    ceiling: dict  # `layer1_ceiling`: what these samples allow any model, per sample

    @property
    def profile(self) -> PathLossProfile:
        return self.fit.profile

    @property
    def pl_at_1m_db(self) -> float:
        return float(np.median(self.profile.pl0_db))

    @property
    def tx_height_m(self) -> float:
        return float(np.median([b.tx_height_m for b in self.budgets]))


def _local_means(g: Group, pred: np.ndarray, meas: np.ndarray, mask: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """5 s power means of prediction and target over the windows inside `mask` (arrays over all samples)."""
    w = g.wins(mask, LOCAL_MEAN_S)
    return power_mean_db(pred, w), power_mean_db(meas, w)


def run_layer1(maeng: list[PathLossSamples], multibw: list[PathLossSamples], pattern: RadiationPattern | None,
               seed: int = 0) -> Layer1Result:
    pg = PatternGain(pattern) if pattern is not None else None
    budgets = [recover_budget(s, pg) for s in maeng]
    cv_budgets = [recover_budget(s, None) for s in multibw]
    groups = prepare(maeng, budgets, pg, seed)
    cv = prepare(multibw, cv_budgets, None, None)
    fit = fit_logdistance(groups, intercept="ci", pattern_terms=True)
    for g in groups:
        g.pl_eff_db = g.pl_db - fit.correction_db(g)  # the effective-pattern target every model is scored on
    fit_free = fit_logdistance(groups, intercept="free", pattern_terms=True)
    fit_radpat = fit_logdistance(groups, intercept="ci", pattern_terms=False)
    k_db = [fit_k_db(g) for g in groups]
    k_factor = KFactorProfile(
        name="calibrated-k",
        source="Maeng LTE 3.51 GHz training segments: moment-method K (Greenstein et al. 1999) of RSRP in 1 s windows",
        altitude_m=fit.profile.altitude_m, k_db=tuple(round(k, 3) for k in k_db),
    )
    d_corr = fit_decorrelation_m(groups, fit)
    two_ray = fit_two_ray(groups, pg, seed=seed)
    uma_offset = -float(np.mean(np.concatenate([uma_loss_db(g, g.train) - g.target_db[g.train] for g in groups])))

    def predict(model: str, g: Group, i: int | None) -> np.ndarray:
        """Prediction over ALL samples of the group (the caller picks the scored ones)."""
        if model == "logdistance":
            return logdist_loss_db(fit.profile, g, slice(None), i)
        if model == "logdistance_free":
            return logdist_loss_db(fit_free.profile, g, slice(None), i)
        if model == "logdistance_radpat":
            return logdist_loss_db(fit_radpat.profile, g, slice(None), i)
        if model == "two_ray":
            return two_ray.predict(g)
        if model == "uma_av":
            return uma_loss_db(g)
        return uma_loss_db(g) + uma_offset

    models: dict = {}
    preds: dict = {}
    for model in MODELS:
        # logdistance_radpat is scored against the rad_pat.mat-only target it was fitted to.
        target = (lambda g: g.pl_db) if model == "logdistance_radpat" else (lambda g: g.target_db)
        entry: dict = {"per_altitude": {}, "crossval_per_altitude": {}}
        acc = {f"{split}_{scale}": ([], []) for split in ("heldout", "crossval") for scale in SCALES}
        for split, gs in (("heldout", groups), ("crossval", cv)):
            for i, g in enumerate(gs):
                p_all = predict(model, g, i if split == "heldout" else None)
                mask = g.test
                preds[(model, split, i)] = p_all[mask]
                lm_p, lm_m = _local_means(g, p_all, target(g), mask)
                per = {"sample": error_metrics(p_all[mask], target(g)[mask]), "local_mean": error_metrics(lm_p, lm_m)}
                key = "per_altitude" if split == "heldout" else "crossval_per_altitude"
                label = f"{g.altitude_m:g}" if split == "heldout" else g.samples.label
                entry[key][label] = per
                acc[f"{split}_sample"][0].append(p_all[mask])
                acc[f"{split}_sample"][1].append(target(g)[mask])
                acc[f"{split}_local_mean"][0].append(lm_p)
                acc[f"{split}_local_mean"][1].append(lm_m)
        for name, (p, m) in acc.items():
            entry[name] = error_metrics(np.concatenate(p), np.concatenate(m)) if p else None
        models[model] = entry
    return Layer1Result(budgets, cv_budgets, fit, fit_free, fit_radpat, k_factor, d_corr, two_ray, uma_offset, models,
                        groups, cv, preds, layer1_ceiling(groups, seed))


def layer1_json(res: Layer1Result) -> dict:
    prof = res.profile
    gain = {t: -float(c)
            for t, c in zip(PATTERN_TERMS, res.fit.pattern_coef)} if res.fit.pattern_coef is not None else None
    return {
        "target": "absolute antenna-compensated path loss PL = EIRP_eff + G_t + G_r (rad_pat.mat at each sample's "
                  "elevation/azimuth/orientation) - RSRP, minus the fitted effective-pattern correction (see "
                  "layer1_fit.py)",
        "split": f"contiguous segments: {BLOCK_S:g} s blocks, {TEST_FRACTION:.0%} held out per file (seeded), "
                 f"{GUARD_S:g} s guards dropped from training beside every held-out block; cross-validation on the "
                 "multi-band campaign, nothing fitted on it",
        "scales": {"sample": "every held-out sample (bounded below by the fast fading)",
                   "local_mean": f"{LOCAL_MEAN_S:g} s power-mean windows inside held-out runs (the twin's window)"},
        "error_convention": "e = predicted - measured; bias_db = mean e",
        "fspl_1m_db": FSPL_1M_DB,
        "pl_at_1m_db": res.pl_at_1m_db,
        "pl_at_1m_minus_fspl_db": res.pl_at_1m_db - FSPL_1M_DB,
        "tx_height_m": res.tx_height_m,
        "link_budget": {"maeng": [b.as_dict() for b in res.budgets],
                        "multibw": [b.as_dict() for b in res.crossval_budgets]},
        "logdistance_params": {
            "nominal_altitude_m": [g.altitude_m for g in res.groups],
            "altitude_m": list(prof.altitude_m), "n": list(prof.n), "pl0_db": list(prof.pl0_db),
            "sigma_db": list(prof.sigma_db),
            "sigma_sample_db": list(res.fit.sigma_sample_db), "fc_ghz": prof.fc_ghz,
            "n_train": [int(g.train.sum()) for g in res.groups], "n_test": [int(g.test.sum()) for g in res.groups],
            "test_blocks": [list(g.split.test_blocks) for g in res.groups],
            "n_blocks": [g.split.n_blocks for g in res.groups],
        },
        "effective_pattern_gain_db": gain,
        "shadowing_decorrelation_m": res.decorrelation_m,
        "k_factor_db": {"altitude_m": list(res.k_factor.altitude_m), "k_db": list(res.k_factor.k_db),
                        "method": res.k_factor.source},
        "logdistance_free_params": {"n": list(res.fit_free.profile.n), "pl0_db": list(res.fit_free.profile.pl0_db),
                                    "sigma_db": list(res.fit_free.profile.sigma_db)},
        "logdistance_radpat_params": {"n": list(res.fit_radpat.profile.n),
                                      "pl0_db": list(res.fit_radpat.profile.pl0_db),
                                      "sigma_db": list(res.fit_radpat.profile.sigma_db)},
        "two_ray_params": res.two_ray.as_dict(),
        "uma_av_offset_db": res.uma_offset_db,
        "crossval_files": [g.samples.label for g in res.crossval_groups],
        "models": res.models,
        "ceiling": res.ceiling,
        "checks": {
            "pl_at_1m_within_10db_of_free_space": abs(res.pl_at_1m_db - FSPL_1M_DB) <= 10.0,
            "logdistance_beats_uma_av_heldout": res.models["logdistance"]["heldout_local_mean"]["rmse_db"]
            < res.models["uma_av"]["heldout_local_mean"]["rmse_db"],
        },
    }
