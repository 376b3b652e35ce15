"""3GPP TR 36.777 V15.0.0 (2017-12), Annex B: channel models for aerial UEs (drones).

Implemented: the aerial-UE rows of Table B-1 (LOS probability) and Table B-2 (path loss and
shadow-fading std) for UMa-AV, RMa-AV and UMi-AV. fc in GHz, distances and heights in metres,
losses in dB; every method takes numpy arrays and broadcasts.

=========  ====================================================  =====================================
model      P_LOS (Table B-1)                                     PL and sigma_SF (Table B-2)
=========  ====================================================  =====================================
UMa-AV     22.5 < h <= 100: d1/d + exp(-d/p1)(1 - d1/d) for      LOS: 28 + 22 log10 d3 + 20 log10 fc,
           d > d1, else 1; p1 = 4300 log10 h - 3800,              sigma 4.64 exp(-0.0066 h)
           d1 = max(460 log10 h - 700, 18);  h > 100: 1          NLOS: -17.5 + (46 - 7 log10 h) log10 d3
                                                                  + 20 log10(40 pi fc / 3), sigma 6
RMa-AV     10 < h <= 40: same form, p1 = max(15021 log10 h        LOS: max(23.9 - 1.8 log10 h, 20) log10 d3
           - 16053, 1000), d1 = max(1350.8 log10 h - 1602, 18);   + 20 log10(40 pi fc / 3),
           h > 40: 1                                              sigma 4.2 exp(-0.0046 h)
                                                                  NLOS: max(PL_LOS, -12 + (35 - 5.3 log10 h)
                                                                  log10 d3 + 20 log10(40 pi fc / 3)), sigma 6
UMi-AV     22.5 < h <= 300: same form, p1 = 233.98 log10 h        LOS: max(PL_FS, 30.9 + (22.25 - 0.5 log10 h)
           - 0.95, d1 = max(294.05 log10 h - 432.94, 18)          log10 d3 + 20 log10 fc),
                                                                  sigma max(5 exp(-0.01 h), 2)
                                                                  NLOS: max(PL_LOS, 32.4 + (43.2 - 7.6
                                                                  log10 h) log10 d3 + 20 log10 fc), sigma 8
=========  ====================================================  =====================================

(h = h_UT, d = d2D, d3 = d3D; PL_FS = 32.4 + 20 log10 fc + 20 log10 d3 is free space.)

Spec vectors (fc 3.51 GHz, h_BS 25 m; checked in tests): UMa-AV h 30 m, d2D 500 m: P_LOS 0.828456,
PL_LOS 98.2840 dB, PL_NLOS 122.0944 dB; h 70 m: P_LOS 0.919969, PL_LOS 98.3220 dB; h 110 m: P_LOS 1.

Validity. Below the aerial height range (22.5 m for UMa/UMi, 10 m for RMa) TR 36.777 falls back
to the terrestrial TR 38.901 models, which this module does not implement; heights are clamped
into [h_min, 300 m] instead (our UAVs fly at 30-110 m, so this only touches the BS-BS pairs the
plan evaluates for completeness). Distances are floored at 1 m. The NLOS formulas are also
evaluated where the table says P_LOS = 1 (they are then never selected by `sample`, and carry
zero weight in `loss_expected_db`). Table B-2 gives UMa-AV NLOS without the max(PL_LOS, .) floor
of RMa-AV/UMi-AV; we follow it, and wherever NLOS can occur (d2D > d1) it exceeds PL_LOS anyway
(their difference, (24 - 7 log10 h) log10 d3 - 13.06 dB, is positive beyond 20 m for h <= 100 m).

Air-to-air links. TR 36.777 has no UAV-UAV channel. With both ends at >= 30 m, above the clutter
these scenarios assume (UMa: buildings below the 25 m BS), the direct ray is unobstructed, so
`evaluate` gives UAV-UAV links the LOS branch (P_LOS = 1) of the same model, with h_UT the higher
altitude: a near-free-space law (slope 20-22 dB/decade) with the model's own frequency scaling.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from ..geometry import MIN_DISTANCE_M, LinkGeometry, PathLossResult
from .base import DEFAULT_FC_GHZ, PathLossOptions, PathLossSpec
from .registry import register

H_UT_MAX_M = 300.0


def _los_probability(d2d_m, d1_m, p1_m) -> np.ndarray:
    """The common Table B-1 form; 1 inside d1 (where the expression would exceed 1)."""
    d = np.maximum(np.asarray(d2d_m, dtype=float), MIN_DISTANCE_M)
    p = d1_m / d + np.exp(-d / p1_m) * (1.0 - d1_m / d)
    return np.where(d <= d1_m, 1.0, np.minimum(p, 1.0))


@dataclass(frozen=True)
class AerialModel:
    """Base of the three TR 36.777 aerial-UE models (fc in GHz, BS antenna height in metres).

    `h_bs_m` is only used where a method must build a geometry itself (`d3d_m`); `evaluate`
    takes the real antenna heights from the link geometry.
    """

    fc_ghz: float = DEFAULT_FC_GHZ
    h_bs_m: float = 25.0
    name = "tr36777"
    samples_los = True
    h_ut_min_m = 22.5  # lower edge of the aerial rows of Tables B-1/B-2
    los_corr_m = 50.0  # LOS/NLOS-state correlation distance, TR 38.901 Table 7.6.3.1-2 (UMa, UMi)

    def _h(self, h_ut_m) -> np.ndarray:
        return np.clip(np.asarray(h_ut_m, dtype=float), self.h_ut_min_m, H_UT_MAX_M)

    @staticmethod
    def _d(d3d_m) -> np.ndarray:
        return np.maximum(np.asarray(d3d_m, dtype=float), MIN_DISTANCE_M)

    @property
    def _fs_term_db(self) -> float:
        # 20 log10(40 pi fc / 3): free space at 1 m with fc in GHz (c = 3e8 m/s as in the TR).
        return 20.0 * np.log10(40.0 * np.pi * self.fc_ghz / 3.0)

    def d3d_m(self, d2d_m, h_ut_m) -> np.ndarray:
        return np.hypot(np.asarray(d2d_m, dtype=float), np.asarray(h_ut_m, dtype=float) - self.h_bs_m)

    # Model-specific rows of Tables B-1/B-2 -------------------------------------------------
    def p_los_at(self, d2d_m, h_ut_m) -> np.ndarray:
        raise NotImplementedError

    def loss_los_db(self, d3d_m, h_ut_m) -> np.ndarray:
        raise NotImplementedError

    def loss_nlos_db(self, d3d_m, h_ut_m) -> np.ndarray:
        raise NotImplementedError

    def sigma_los_db(self, h_ut_m) -> np.ndarray:
        raise NotImplementedError

    def sigma_nlos_db(self, h_ut_m) -> np.ndarray:
        raise NotImplementedError

    # Derived quantities ----------------------------------------------------------------------
    def p_los(self, geom: LinkGeometry) -> np.ndarray:
        """P_LOS per link; air-to-air links are LOS (see the module docstring)."""
        return np.where(geom.air_to_air, 1.0, self.p_los_at(geom.d2d_m, geom.h_air_m))

    def loss_db(self, geom: LinkGeometry) -> np.ndarray:
        return self.evaluate(geom, None).loss_db

    def loss_expected_db(self, d2d_m, d3d_m, h_ut_m) -> np.ndarray:
        """Path loss averaged in dB over the LOS state: P PL_LOS + (1 - P) PL_NLOS."""
        p = self.p_los_at(d2d_m, h_ut_m)
        return p * self.loss_los_db(d3d_m, h_ut_m) + (1.0 - p) * self.loss_nlos_db(d3d_m, h_ut_m)

    def sample(self, d2d_m, d3d_m, h_ut_m, uniform) -> PathLossResult:
        """LOS iff uniform < P_LOS; `uniform` in [0, 1) per link (correlated over time by the
        caller, as TR 38.901 sec. 7.6.3.3 does for the LOS state)."""
        los = np.asarray(uniform, dtype=float) < self.p_los_at(d2d_m, h_ut_m)
        loss = np.where(los, self.loss_los_db(d3d_m, h_ut_m), self.loss_nlos_db(d3d_m, h_ut_m))
        sigma = np.where(los, self.sigma_los_db(h_ut_m), self.sigma_nlos_db(h_ut_m))
        return PathLossResult(loss_db=loss, sigma_db=sigma, los=los)

    def evaluate(self, geom: LinkGeometry, los_uniform: np.ndarray | None = None) -> PathLossResult:
        """Per-link loss. With `los_uniform` the LOS state is sampled; without it the loss is
        the LOS-probability-weighted mean and `los` is None. Air-to-air links are LOS."""
        h = geom.h_air_m
        if los_uniform is None:
            p = self.p_los(geom)
            loss = p * self.loss_los_db(geom.d3d_m, h) + (1.0 - p) * self.loss_nlos_db(geom.d3d_m, h)
            # Std of the mixture's Gaussian parts, without the spread between the two means.
            var = p * self.sigma_los_db(h) ** 2 + (1.0 - p) * self.sigma_nlos_db(h) ** 2
            return PathLossResult(loss_db=loss, sigma_db=np.sqrt(var), los=None)
        u = np.where(geom.air_to_air, 0.0, np.asarray(los_uniform, dtype=float))  # 0 < P always
        return self.sample(geom.d2d_m, geom.d3d_m, h, u)


@dataclass(frozen=True)
class UMaAV(AerialModel):
    """Urban macro with aerial UEs (TR 38.901 UMa BS height is 25 m)."""

    name = "uma"

    def p_los_at(self, d2d_m, h_ut_m) -> np.ndarray:
        h = self._h(h_ut_m)
        lh = np.log10(h)
        p = _los_probability(d2d_m, np.maximum(460.0 * lh - 700.0, 18.0), 4300.0 * lh - 3800.0)
        return np.where(h > 100.0, 1.0, p)

    def loss_los_db(self, d3d_m, h_ut_m) -> np.ndarray:
        # Independent of h_UT inside the aerial range; broadcast so shapes follow both inputs.
        d, _ = np.broadcast_arrays(self._d(d3d_m), np.asarray(h_ut_m, dtype=float))
        return 28.0 + 22.0 * np.log10(d) + 20.0 * np.log10(self.fc_ghz)

    def loss_nlos_db(self, d3d_m, h_ut_m) -> np.ndarray:
        h = self._h(h_ut_m)
        return -17.5 + (46.0 - 7.0 * np.log10(h)) * np.log10(self._d(d3d_m)) + self._fs_term_db

    def sigma_los_db(self, h_ut_m) -> np.ndarray:
        return 4.64 * np.exp(-0.0066 * self._h(h_ut_m))

    def sigma_nlos_db(self, h_ut_m) -> np.ndarray:
        return np.full(np.shape(h_ut_m), 6.0)


@dataclass(frozen=True)
class RMaAV(AerialModel):
    """Rural macro with aerial UEs (TR 38.901 RMa default BS height is 35 m)."""

    h_bs_m: float = 35.0
    name = "rma"
    h_ut_min_m = 10.0
    los_corr_m = 60.0

    def p_los_at(self, d2d_m, h_ut_m) -> np.ndarray:
        h = self._h(h_ut_m)
        lh = np.log10(h)
        d1 = np.maximum(1350.8 * lh - 1602.0, 18.0)
        p1 = np.maximum(15021.0 * lh - 16053.0, 1000.0)
        return np.where(h > 40.0, 1.0, _los_probability(d2d_m, d1, p1))

    def loss_los_db(self, d3d_m, h_ut_m) -> np.ndarray:
        slope = np.maximum(23.9 - 1.8 * np.log10(self._h(h_ut_m)), 20.0)
        return slope * np.log10(self._d(d3d_m)) + self._fs_term_db

    def loss_nlos_db(self, d3d_m, h_ut_m) -> np.ndarray:
        h = self._h(h_ut_m)
        nlos = -12.0 + (35.0 - 5.3 * np.log10(h)) * np.log10(self._d(d3d_m)) + self._fs_term_db
        return np.maximum(self.loss_los_db(d3d_m, h_ut_m), nlos)

    def sigma_los_db(self, h_ut_m) -> np.ndarray:
        return 4.2 * np.exp(-0.0046 * self._h(h_ut_m))

    def sigma_nlos_db(self, h_ut_m) -> np.ndarray:
        return np.full(np.shape(h_ut_m), 6.0)


@dataclass(frozen=True)
class UMiAV(AerialModel):
    """Urban micro (street canyon) with aerial UEs (TR 38.901 UMi BS height is 10 m)."""

    h_bs_m: float = 10.0
    name = "umi"

    def p_los_at(self, d2d_m, h_ut_m) -> np.ndarray:
        lh = np.log10(self._h(h_ut_m))
        return _los_probability(d2d_m, np.maximum(294.05 * lh - 432.94, 18.0), 233.98 * lh - 0.95)

    def loss_los_db(self, d3d_m, h_ut_m) -> np.ndarray:
        h, d = self._h(h_ut_m), self._d(d3d_m)
        free_space = 32.4 + 20.0 * np.log10(self.fc_ghz) + 20.0 * np.log10(d)
        los = 30.9 + (22.25 - 0.5 * np.log10(h)) * np.log10(d) + 20.0 * np.log10(self.fc_ghz)
        return np.maximum(free_space, los)

    def loss_nlos_db(self, d3d_m, h_ut_m) -> np.ndarray:
        h, d = self._h(h_ut_m), self._d(d3d_m)
        nlos = 32.4 + (43.2 - 7.6 * np.log10(h)) * np.log10(d) + 20.0 * np.log10(self.fc_ghz)
        return np.maximum(self.loss_los_db(d3d_m, h_ut_m), nlos)

    def sigma_los_db(self, h_ut_m) -> np.ndarray:
        return np.maximum(5.0 * np.exp(-0.01 * self._h(h_ut_m)), 2.0)

    def sigma_nlos_db(self, h_ut_m) -> np.ndarray:
        return np.full(np.shape(h_ut_m), 8.0)


def _builder(cls: type[AerialModel]):
    def build(o: PathLossOptions) -> AerialModel:
        m = cls(fc_ghz=o.carrier_ghz)
        return m if o.h_bs_m is None else replace(m, h_bs_m=o.h_bs_m)
    return build


_STANDARD = "3GPP TR 36.777 V15.0.0 (2017-12) Annex B, Tables B-1 (P_LOS) and B-2 (PL, sigma_SF), aerial-UE rows"
for _name, _cls, _what in (
    ("3gpp", UMaAV, "urban macro (the paper's name for uma)"),
    ("uma", UMaAV, "urban macro"),
    ("rma", RMaAV, "rural macro"),
    ("umi", UMiAV, "urban micro"),
):
    register(PathLossSpec(
        name=_name, model=_cls, standard=f"{_STANDARD}, {_cls.__name__[:-2]}-AV",
        summary=f"TR 36.777 {_what} with aerial UEs, LOS state sampled", build=_builder(_cls),
    ))

__all__ = ["AerialModel", "RMaAV", "UMaAV", "UMiAV"]
