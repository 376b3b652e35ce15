"""Small-scale fading: Rician with an altitude-dependent K factor, averaged over a window.

A plan window lasts seconds; the small-scale fading of a UAV link decorrelates within
milliseconds (Clarke's coherence time T_c = 0.423 / f_D, Rappaport, Wireless Communications,
2nd ed., sec. 5.4.3: at 3.5 GHz and 5 m/s, f_D = 58 Hz and T_c = 7 ms). A window therefore
sees the whole fading distribution, and what the emulated link must carry is the window's
*expectation* over it: loss = E_g[f(SNR g)], g = |h|^2 the fading power gain (E g = 1).

Distribution: g ~ Rician power with K factor K (ratio of the direct ray to the scattered
power): (2 (K + 1)) g is noncentral chi-square with 2 degrees of freedom and non-centrality
2 K. K = 0 is Rayleigh; K -> inf no fading. The emulator's shaper applies one loss per link
and window, so the expectation is the only place fading can act - and it is what makes loss
rise smoothly with distance instead of switching from 0 to 1 within a dB.

Expectation: quadrature on the quantiles of g. Nodes are the Rician quantiles at the
midpoints (in logit space) of `N_NODES` bins equally spaced in logit(u) over [-16, 16], each
weighted by its probability, so both tails (deep fades and lucky peaks, down to 1e-7) are
resolved; the nodes are tabulated on a 0.25 dB K grid once per process (scipy `ncx2.ppf`) and
a K between two grid points mixes the two rows linearly. Each row is scaled to E g = 1
exactly. Deterministic: a pure function of its inputs.

K(h). Two sources, both as `KFactorProfile`:
* ``tr36777_uma_av`` - 3GPP TR 36.777 V15.0.0 (2017-12), Annex B.1.2, Table B.1.2-2 (UMa-AV,
  LOS, fast-fading Alternative 2): mu_K = 4.217 log10(h_UT) + 5.787 dB, 22.5 m < h_UT <= 300 m
  (spec vectors: 30 m -> 12.016 dB, 110 m -> 14.396 dB). The paper profile uses it.
* a table per altitude measured by `uavcas calibrate` on the AERPAW Maeng et al. LTE flights
  (moment-method K of the RSRP about its 40-wavelength local mean; see
  `uavcas.calibration.layer1_pathloss`). The calibrated profile uses it.
The altitude is the link's aerial end (the higher UAV for UAV-UAV links), as for path loss.
"""

from __future__ import annotations

from functools import lru_cache
from typing import Literal

import numpy as np
from pydantic import BaseModel, ConfigDict, model_validator
from scipy.special import expit
from scipy.stats import ncx2

K_GRID_DB = np.round(np.arange(-10.0, 40.0 + 1e-9, 0.25), 2)  # below -10 dB: Rayleigh in effect
N_NODES = 256
_LOGIT_SPAN = 16.0


class KFactorProfile(BaseModel):
    """K factor (dB) against the aerial end's altitude: a measured table or the TR 36.777 law."""

    model_config = ConfigDict(frozen=True, extra="forbid")

    name: str
    source: str = ""
    kind: Literal["table", "tr36777_uma_av"] = "table"
    altitude_m: tuple[float, ...] = ()
    k_db: tuple[float, ...] = ()

    @model_validator(mode="after")
    def _check(self) -> KFactorProfile:
        if self.kind == "table":
            if not self.altitude_m or len(self.altitude_m) != len(self.k_db):
                raise ValueError("a K table needs altitude_m and k_db of the same non-zero length")
            if np.any(np.diff(self.altitude_m) <= 0):
                raise ValueError("altitude_m must be strictly increasing")
        return self

    def at(self, h_m) -> np.ndarray:
        """K (dB) at altitude(s) h: the law, or the table interpolated linearly (clamped outside)."""
        h = np.asarray(h_m, dtype=float)
        if self.kind == "tr36777_uma_av":
            return tr36777_uma_av_k_db(h)
        return np.interp(h, self.altitude_m, self.k_db)


def tr36777_uma_av_k_db(h_ut_m) -> np.ndarray:
    """TR 36.777 Table B.1.2-2, UMa-AV LOS: mean K = 4.217 log10(h_UT) + 5.787 dB (h clamped
    into the table's 22.5-300 m)."""
    h = np.clip(np.asarray(h_ut_m, dtype=float), 22.5, 300.0)
    return 4.217 * np.log10(h) + 5.787


TR36777_UMA_AV_K = KFactorProfile(
    name="tr36777-uma-av",
    source="3GPP TR 36.777 V15.0.0 Table B.1.2-2, UMa-AV LOS: K = 4.217 log10(h_UT) + 5.787 dB",
    kind="tr36777_uma_av",
)


@lru_cache(maxsize=1)
def _quantile_table() -> tuple[np.ndarray, np.ndarray]:
    """(gain_db (len K_GRID_DB, N_NODES), weights (N_NODES,)) of the Rician power quantiles."""
    z = np.linspace(-_LOGIT_SPAN, _LOGIT_SPAN, N_NODES + 1)
    edges = np.r_[0.0, expit(z[1:-1]), 1.0]
    weights = np.diff(edges)
    u = expit((z[:-1] + z[1:]) / 2.0)
    k = 10.0 ** (K_GRID_DB / 10.0)
    g = ncx2.ppf(u[None, :], 2, 2.0 * k[:, None]) / (2.0 * (k[:, None] + 1.0))
    g = g / (g @ weights)[:, None]  # E g = 1 exactly under the quadrature
    gain_db = 10.0 * np.log10(g)
    gain_db.setflags(write=False)
    weights.setflags(write=False)
    return gain_db, weights


def fading_nodes(k_db) -> tuple[np.ndarray, np.ndarray]:
    """Quadrature of the fading gain for each link: (gain_db (k, 2N), weight (k, 2N)).

    E[f(SNR g)] ~= sum_j weight[:, j] f(snr_db[:, None] + gain_db[:, j]). K outside the grid is
    clamped to it (-10 dB is Rayleigh to within the quadrature's accuracy; 40 dB is no fading)."""
    table, w = _quantile_table()
    kk = np.clip(np.asarray(k_db, dtype=float).ravel(), K_GRID_DB[0], K_GRID_DB[-1])
    pos = (kk - K_GRID_DB[0]) / (K_GRID_DB[1] - K_GRID_DB[0])
    lo = np.minimum(np.floor(pos).astype(np.int64), len(K_GRID_DB) - 2)
    frac = (pos - lo)[:, None]
    gain = np.concatenate([table[lo], table[lo + 1]], axis=1)
    weight = np.concatenate([(1.0 - frac) * w[None, :], frac * w[None, :]], axis=1)
    return gain, weight


def expect(fn, snr_db, k_db) -> np.ndarray:
    """E over Rician fading of fn(instantaneous SNR in dB) per link; fn maps (k, m) -> (k, m)."""
    snr = np.asarray(snr_db, dtype=float).ravel()
    gain, weight = fading_nodes(np.broadcast_to(np.asarray(k_db, dtype=float), np.shape(snr_db)))
    return np.sum(weight * fn(snr[:, None] + gain), axis=1).reshape(np.shape(snr_db))
