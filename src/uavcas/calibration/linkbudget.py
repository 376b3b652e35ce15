"""The explicit link budget that turns received power into absolute path loss.

Each processed file carries, per sample, the power its authors *predicted* with free-space loss
and the antenna pattern applied (``RSRP_PL_free``). That prediction is

    P_free,i = EIRP_eff + G_i - FSPL(d3D_i, fc)                       (dBm, or sounder dB)

with EIRP_eff the effective transmit level (for Maeng LTE: per 15 kHz resource element, since
RSRP is a per-RE power) and G_i = G_tx(towards UAV) + G_rx(towards tower) the pattern gain of
sample i. Adding FSPL back gives K_i = EIRP_eff + G_i exactly, so the budget is recovered per
sample without guessing the authors' interpolation. The absolute (antenna-compensated) path loss
of a measurement is then

    PL_i = EIRP_eff + G_i - P_rx,i = K_i - P_rx,i = FSPL(d3D_i) + (P_free,i - P_rx,i).

The target the fit uses is computed with OUR pattern evaluation, not the authors' column:

    PL_i = EIRP_eff + G_t(elev_i, azim_i + 90) + G_r(elev_i, azim_i - ori_i) - P_rx,i

(`absolute_pathloss_db` with a pattern), so the antenna gains come from ``rad_pat.mat`` at each
sample's elevation, azimuth and UAV orientation; K_i only fixes the one constant EIRP_eff.

To split K_i into EIRP_eff and G_i we evaluate the measured pattern (``rad_pat.mat``) ourselves:
G_i = G_t(elev_i, azim_i + 90 deg) + G_r(elev_i, azim_i - ori_i), bilinear on the 3-degree grid
(azimuth periodic). That angle convention is the one, among the natural candidates (azimuth
measured from north or east, either sense; UAV heading added or subtracted; elevation up or
down), that reproduces the authors' K_i best - residual std 0.5-0.85 dB per altitude, the rest
being their interpolation/tilt details - and EIRP_eff = mean(K_i - G_i), reported with that
residual so a user can judge it. Where a file has no angles (multi-band) EIRP_eff is reported as
median(K_i) and G_i = K_i - EIRP_eff (the pattern is then only implicit).

Carrier: Maeng LTE 3.51 GHz (AERPAW LW1). Multi-band sounder: 3.3 GHz, the carrier the paper
states for this (Guerses-Sichitiu) campaign; the processed files do not record it. The carrier
only enters through FSPL(d, fc), i.e. as 20 log10(fc) on every sample.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.interpolate import RegularGridInterpolator

from uavcas.channel import free_space_loss_db

from .loaders import PathLossSamples, RadiationPattern

MAENG_FC_GHZ = 3.51
MULTIBW_FC_GHZ = 3.3


def carrier_ghz(campaign: str) -> float:
    return {"maeng": MAENG_FC_GHZ, "multibw": MULTIBW_FC_GHZ}.get(campaign, MAENG_FC_GHZ)


class PatternGain:
    """G_tx + G_rx (dB) of the Maeng measurement geometry from the measured pattern tables."""

    def __init__(self, pattern: RadiationPattern):
        ti, pi_ = np.argsort(pattern.theta_deg), np.argsort(pattern.phi_deg)
        th, ph = pattern.theta_deg[ti], pattern.phi_deg[pi_]
        # Periodic in azimuth: tile one period each side so interpolation wraps around +-180.
        ph3 = np.concatenate([ph - 360.0, ph, ph + 360.0])

        def table(g: np.ndarray) -> RegularGridInterpolator:
            g = np.asarray(g, float)[ti][:, pi_]
            return RegularGridInterpolator((th, ph3), np.concatenate([g, g, g], axis=1))

        self._gt, self._gr = table(pattern.g_tx_db), table(pattern.g_rx_db)
        self.source = pattern.source

    @staticmethod
    def _pts(theta_deg, phi_deg) -> np.ndarray:
        return np.c_[np.clip(theta_deg, -90.0, 90.0), (np.asarray(phi_deg) + 180.0) % 360.0 - 180.0]

    def gain_db(self, elev_rad, azim_rad, ori_rad) -> np.ndarray:
        el, az, ori = (np.degrees(np.asarray(a, float)) for a in (elev_rad, azim_rad, ori_rad))
        return self._gt(self._pts(el, az + 90.0)) + self._gr(self._pts(el, az - ori))


@dataclass(frozen=True)
class BudgetFit:
    """The recovered budget of one file (see module docstring)."""

    label: str
    fc_ghz: float
    eirp_eff_dbm: float  # EIRP_eff (Maeng: per resource element)
    gain_mean_db: float  # mean pattern gain G_i over the samples
    gain_std_db: float
    pattern_residual_db: float | None  # std of K_i - EIRP_eff - G_pattern,i (None: no angles)
    tx_height_m: float  # transmitter antenna height from the geometry

    def as_dict(self) -> dict:
        return {k: (round(v, 4) if isinstance(v, float) else v) for k, v in self.__dict__.items()}


def budget_term_db(s: PathLossSamples) -> np.ndarray:
    """K_i = EIRP_eff + G_i, exactly, from the file's own free-space prediction."""
    return s.pred_free_dbm + free_space_loss_db(s.d3d_m, carrier_ghz(s.campaign))


def absolute_pathloss_db(s: PathLossSamples, budget: BudgetFit | None = None,
                         pattern: PatternGain | None = None) -> np.ndarray:
    """Antenna-compensated absolute path loss (dB) per sample: EIRP_eff + G_pattern - P_rx with
    our pattern gains when `pattern` and the sample angles are there, else K_i - P_rx with the
    file's own budget term (the multi-band files: no angles for the Maeng pattern)."""
    if budget is not None and pattern is not None and _has_angles(s):
        return budget.eirp_eff_dbm + pattern.gain_db(s.elev_rad, s.azim_rad, s.ori_rad) - s.rx_dbm
    return budget_term_db(s) - s.rx_dbm


def _has_angles(s: PathLossSamples) -> bool:
    return s.elev_rad is not None and s.azim_rad is not None and s.ori_rad is not None


def tx_height_m(s: PathLossSamples) -> float:
    """Transmitter antenna height from d3D^2 = d2D^2 + (h_UAV - h_tx)^2 (UAV above the tower)."""
    dz = np.sqrt(np.maximum(s.d3d_m**2 - s.d2d_m**2, 0.0))
    return float(np.median(s.height_m - dz))


def recover_budget(s: PathLossSamples, pattern: PatternGain | None) -> BudgetFit:
    k = budget_term_db(s)
    residual = None
    if pattern is not None and _has_angles(s):
        g = pattern.gain_db(s.elev_rad, s.azim_rad, s.ori_rad)
        eirp = float(np.mean(k - g))
        residual = float(np.std(k - eirp - g))
    else:
        eirp = float(np.median(k))
    gain = k - eirp
    return BudgetFit(
        label=f"{s.campaign} {s.label}", fc_ghz=carrier_ghz(s.campaign), eirp_eff_dbm=eirp,
        gain_mean_db=float(gain.mean()), gain_std_db=float(gain.std()), pattern_residual_db=residual,
        tx_height_m=tx_height_m(s),
    )
