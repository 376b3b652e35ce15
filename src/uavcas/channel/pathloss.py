"""Path-loss models: altitude-dependent log-distance, TR 36.777 aerial (re-exported), two-ray,
free space, and `make_pathloss` for the scenario string's names.

Every model has ``evaluate(geom: LinkGeometry, los_uniform=None) -> PathLossResult`` (median loss
in dB, the shadowing std to apply, and the LOS state where the model has one).

Log-distance on an absolute scale, anchored to the carrier
----------------------------------------------------------
PL(d, h, fc) = PL0(h) + 20 log10(fc / fc_p) + 10 n(h) log10(d / d0),   d = 3-D distance, d0 = 1 m

with X ~ N(0, sigma(h)^2) added by the shadowing process. n, PL0 and sigma are given at
calibration altitudes and linearly interpolated in h, clamped to the end values outside
(`np.interp`). PL0 is the loss at d0 at the profile's carrier fc_p; at another carrier fc the
whole curve moves by Friis' 20 log10(fc / fc_p) (the loss at d0 is free space plus a
frequency-independent excess, so the excess and the slope carry over). That carrier anchor is
what lets one fitted profile serve another band (calibration checks it on the multi-band
campaign, fitted at 3.51 GHz, scored at 3.3 GHz).

Profiles. The twin's default is the *calibrated* profile shipped with uavcas (fitted by
`uavcas calibrate` on the AERPAW Maeng et al. LTE flights; `uavcas.twin.profile`). This module
holds the paper's numbers, the library fallback when no profile is given:

The paper's table ``tab:pathloss_params`` (h = 30, 50, 70, 90, 110 m: n = 1.541, 1.593, 1.849,
1.881, 1.860; PL0 = 15.23, 13.65, 4.01, 3.16, 3.37 dB; sigma = 3.70, 3.73, 4.08, 4.48, 4.46 dB)
was fitted to RSRP on a *relative* scale: a PL0 of 3-15 dB at 1 m is 30-40 dB less than free
space allows, which is why the authors' code saw SNR >= 41 dB on every link. The
``paper-anchored`` profile keeps the fitted exponents and spreads and restores an absolute
level with ONE constant offset for all altitudes:

    PL0(h) = FSPL(d0 = 1 m, 3.51 GHz) + (PL0_paper(h) - min_h PL0_paper(h))
           = 43.35 dB + (PL0_paper(h) - 3.16 dB)     ->  55.42, 53.84, 44.20, 43.35, 43.56 dB

so the least-lossy calibration altitude (90 m) sits exactly at free space at d0 and no altitude
is below it there. A common offset keeps what the fit did measure - the difference between
altitudes, which it took from one receiver chain, so it is not affected by the unknown absolute
calibration - whereas anchoring each altitude separately at 43.35 dB would discard it. With
n < 2 the curves fall below free space far from d0 (at 500 m h = 30 m gives 97.0 dB against
97.3 dB free space); that is the fitted slope, kept as fitted. The raw paper numbers stay
available as the ``paper-relative`` profile for parity with the authors' data.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

import numpy as np
from pydantic import BaseModel, ConfigDict, Field, model_validator
from scipy.constants import c as SPEED_OF_LIGHT_M_S

from uavcas.vocabulary import PATHLOSS_MODELS

from .geometry import MIN_DISTANCE_M, LinkGeometry, PathLossResult
from .tr36777 import AerialModel, RMaAV, UMaAV, UMiAV

DEFAULT_FC_GHZ = 3.51  # AERPAW measurement carrier (Maeng et al.)


def free_space_loss_db(d_m, fc_ghz: float = DEFAULT_FC_GHZ) -> np.ndarray:
    """Friis: 20 log10(4 pi d f / c)."""
    d = np.maximum(np.asarray(d_m, dtype=float), MIN_DISTANCE_M)
    return 20.0 * np.log10(4.0 * np.pi * d * fc_ghz * 1e9 / SPEED_OF_LIGHT_M_S)


class PathLossProfile(BaseModel):
    """Per-altitude log-distance parameters; JSON-serialisable so calibration can write one."""

    model_config = ConfigDict(frozen=True, extra="forbid")

    name: str
    source: str = ""  # where the numbers come from (paper table, calibration run, ...)
    fc_ghz: float = Field(DEFAULT_FC_GHZ, gt=0)
    d0_m: float = Field(1.0, gt=0)
    altitude_m: tuple[float, ...]
    n: tuple[float, ...]  # path-loss exponent
    pl0_db: tuple[float, ...]  # loss at d0
    sigma_db: tuple[float, ...]  # shadowing std

    @model_validator(mode="after")
    def _check(self) -> PathLossProfile:
        k = len(self.altitude_m)
        if k == 0 or any(len(v) != k for v in (self.n, self.pl0_db, self.sigma_db)):
            raise ValueError("altitude_m, n, pl0_db and sigma_db need the same non-zero length")
        if np.any(np.diff(self.altitude_m) <= 0):
            raise ValueError("altitude_m must be strictly increasing")
        if min(self.sigma_db) < 0:
            raise ValueError("sigma_db must be >= 0")
        return self

    def at(self, h_m) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(n, PL0, sigma) at altitude(s) h: linear between calibration altitudes, clamped outside."""
        h = np.asarray(h_m, dtype=float)
        xs = self.altitude_m
        return np.interp(h, xs, self.n), np.interp(h, xs, self.pl0_db), np.interp(h, xs, self.sigma_db)


_PAPER_ALT_M = (30.0, 50.0, 70.0, 90.0, 110.0)
_PAPER_N = (1.541, 1.593, 1.849, 1.881, 1.860)
_PAPER_PL0_DB = (15.23, 13.65, 4.01, 3.16, 3.37)
_PAPER_SIGMA_DB = (3.70, 3.73, 4.08, 4.48, 4.46)

PAPER_RELATIVE_PROFILE = PathLossProfile(
    name="paper-relative",
    source="uavcas paper, table tab:pathloss_params (relative RSRP scale, as published)",
    altitude_m=_PAPER_ALT_M, n=_PAPER_N, pl0_db=_PAPER_PL0_DB, sigma_db=_PAPER_SIGMA_DB,
)
_FSPL_D0_DB = float(free_space_loss_db(1.0, DEFAULT_FC_GHZ))  # 43.35 dB
PAPER_ANCHORED_PROFILE = PathLossProfile(
    name="paper-anchored",
    source="tab:pathloss_params n and sigma; PL0 shifted by one constant so min PL0 = FSPL(1 m, 3.51 GHz)",
    altitude_m=_PAPER_ALT_M,
    n=_PAPER_N,
    pl0_db=tuple(round(_FSPL_D0_DB + p - min(_PAPER_PL0_DB), 4) for p in _PAPER_PL0_DB),
    sigma_db=_PAPER_SIGMA_DB,
)
PROFILES = {p.name: p for p in (PAPER_ANCHORED_PROFILE, PAPER_RELATIVE_PROFILE)}


def get_profile(profile: PathLossProfile | str | None) -> PathLossProfile:
    """A profile object, or one of this module's by name; None -> ``paper-anchored`` (the library
    fallback - the twin passes its own profile, calibrated by default)."""
    if profile is None:
        return PAPER_ANCHORED_PROFILE
    if isinstance(profile, PathLossProfile):
        return profile
    try:
        return PROFILES[profile]
    except KeyError:
        raise ValueError(f"unknown path-loss profile {profile!r}; known: {sorted(PROFILES)}") from None


@dataclass(frozen=True)
class LogDistance:
    """Altitude-dependent log-distance. The altitude used is the link's aerial end (the UAV for
    UAV-BS links, as in the fit; the higher UAV for UAV-UAV links, one rule for both kinds).
    `fc_ghz` (None: the profile's carrier) moves the curve by 20 log10(fc / profile.fc_ghz)."""

    profile: PathLossProfile = PAPER_ANCHORED_PROFILE
    fc_ghz: float | None = None
    name = "logdist"

    @property
    def carrier_shift_db(self) -> float:
        fc = self.profile.fc_ghz if self.fc_ghz is None else self.fc_ghz
        return float(20.0 * np.log10(fc / self.profile.fc_ghz))

    def loss_db(self, d3d_m, h_m) -> np.ndarray:
        n, pl0, _ = self.profile.at(h_m)
        d = np.maximum(np.asarray(d3d_m, dtype=float), self.profile.d0_m)
        return pl0 + self.carrier_shift_db + 10.0 * n * np.log10(d / self.profile.d0_m)

    def sigma_db(self, h_m) -> np.ndarray:
        return self.profile.at(h_m)[2]

    def evaluate(self, geom: LinkGeometry, los_uniform: np.ndarray | None = None) -> PathLossResult:
        return PathLossResult(self.loss_db(geom.d3d_m, geom.h_air_m), self.sigma_db(geom.h_air_m), None)


@dataclass(frozen=True)
class FreeSpace:
    """Friis free-space loss on the 3-D distance; `sigma_db` (default 0: deterministic)."""

    fc_ghz: float = DEFAULT_FC_GHZ
    sigma_db: float = 0.0
    name = "freespace"

    def loss_db(self, d3d_m) -> np.ndarray:
        return free_space_loss_db(d3d_m, self.fc_ghz)

    def evaluate(self, geom: LinkGeometry, los_uniform: np.ndarray | None = None) -> PathLossResult:
        loss = self.loss_db(geom.d3d_m)
        return PathLossResult(loss, np.full(loss.shape, self.sigma_db), None)


@dataclass(frozen=True)
class TwoRay:
    """Direct ray plus one ray reflected by flat ground, summed coherently (Rappaport, Wireless
    Communications, 2nd ed., secs. 4.5-4.6: Fresnel reflection and the two-ray model):

        PL = -20 log10( lambda / (4 pi) * | e^{-jk r1} / r1 + Gamma(psi) e^{-jk r2} / r2 | )

    r1 = sqrt(d2^2 + (ht - hr)^2), r2 = sqrt(d2^2 + (ht + hr)^2), grazing angle sin(psi) =
    (ht + hr) / r2. Gamma is the Fresnel coefficient of ground with complex permittivity
    eps = eps_r - j 60 sigma lambda. Default ground: ITU-R P.527 "medium dry ground" (eps_r 15,
    sigma 1e-3 S/m). Default polarisation: vertical, as for the vertical dipoles/monopoles
    typical of UAV radios; "horizontal" is available (and Gamma = -1
    in the grazing limit for both). Antenna heights come from the geometry (BS mast, UAV
    altitude). The result has the two-ray model's deep interference nulls; `sigma_db`
    (default 0) adds shadowing on top if wanted.
    """

    fc_ghz: float = DEFAULT_FC_GHZ
    eps_r: float = 15.0
    conductivity_s_m: float = 1e-3
    polarisation: Literal["vertical", "horizontal"] = "vertical"
    sigma_db: float = 0.0
    name = "tworay"

    def reflection_coefficient(self, sin_psi) -> np.ndarray:
        lam = SPEED_OF_LIGHT_M_S / (self.fc_ghz * 1e9)
        eps = self.eps_r - 1j * 60.0 * self.conductivity_s_m * lam
        s = np.asarray(sin_psi, dtype=float)
        root = np.sqrt(eps - (1.0 - s**2))
        if self.polarisation == "vertical":
            return (eps * s - root) / (eps * s + root)
        return (s - root) / (s + root)

    def loss_db(self, d2d_m, h_tx_m, h_rx_m) -> np.ndarray:
        lam = SPEED_OF_LIGHT_M_S / (self.fc_ghz * 1e9)
        d2 = np.asarray(d2d_m, dtype=float)
        ht, hr = np.asarray(h_tx_m, dtype=float), np.asarray(h_rx_m, dtype=float)
        r1 = np.maximum(np.hypot(d2, ht - hr), MIN_DISTANCE_M)
        r2 = np.hypot(d2, ht + hr)
        gamma = self.reflection_coefficient((ht + hr) / r2)
        k = 2.0 * np.pi / lam
        # Phase relative to the direct ray: only the path difference matters (and keeps precision).
        field = 1.0 / r1 + gamma * np.exp(-1j * k * (r2 - r1)) / r2
        return -20.0 * np.log10(lam / (4.0 * np.pi) * np.maximum(np.abs(field), 1e-12))

    def evaluate(self, geom: LinkGeometry, los_uniform: np.ndarray | None = None) -> PathLossResult:
        loss = self.loss_db(geom.d2d_m, geom.h_ground_m, geom.h_air_m)
        return PathLossResult(loss, np.full(loss.shape, self.sigma_db), None)


PathLossModel = LogDistance | FreeSpace | TwoRay | AerialModel
PATHLOSS_NAMES = PATHLOSS_MODELS  # the scenario vocabulary's names


def make_pathloss(
    name: str,
    profile: PathLossProfile | str | None = None,
    fc_ghz: float | None = None,
    h_bs_m: float | None = None,
) -> PathLossModel:
    """Model for a scenario-string name: logdist, 3gpp (= UMa-AV), uma, rma, umi, tworay,
    freespace, at carrier `fc_ghz` (None: 3.51 GHz, or the log-distance profile's own carrier).
    `profile` applies to logdist only (default ``paper-anchored``); `h_bs_m` overrides the
    3GPP models' default BS height (used only where no geometry gives one)."""
    if name == "logdist":
        return LogDistance(get_profile(profile), fc_ghz)
    fc_ghz = DEFAULT_FC_GHZ if fc_ghz is None else fc_ghz
    if name in ("3gpp", "uma", "rma", "umi"):
        cls = {"3gpp": UMaAV, "uma": UMaAV, "rma": RMaAV, "umi": UMiAV}[name]
        return cls(fc_ghz=fc_ghz) if h_bs_m is None else cls(fc_ghz=fc_ghz, h_bs_m=h_bs_m)
    if name == "tworay":
        return TwoRay(fc_ghz=fc_ghz)
    if name == "freespace":
        return FreeSpace(fc_ghz=fc_ghz)
    raise ValueError(f"unknown path-loss model {name!r}; expected one of {', '.join(PATHLOSS_NAMES)}")


__all__ = [
    "PAPER_ANCHORED_PROFILE", "PAPER_RELATIVE_PROFILE", "PATHLOSS_NAMES", "PROFILES", "AerialModel",
    "FreeSpace", "LinkGeometry", "LogDistance", "PathLossModel", "PathLossProfile",
    "PathLossResult", "RMaAV", "TwoRay", "UMaAV", "UMiAV", "free_space_loss_db", "get_profile",
    "make_pathloss",
]
