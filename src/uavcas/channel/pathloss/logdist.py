"""Altitude-dependent close-in log-distance, anchored to the carrier, and its profiles.

Standard: the close-in (CI) free-space reference model (T. S. Rappaport et al., "Wideband
millimeter-wave propagation measurements and channel models for future wireless communication
system design", IEEE Trans. Commun. 63(9), 2015; Sun et al., IEEE Trans. Veh. Technol. 65(5),
2016), with the exponent, the 1 m loss and the shadowing spread given per altitude. What the
code implements is the formula below; the CI fit proper (1 m loss = free space) is the calibrated
profile's (`uavcas.calibration.layer1_fit.fit_logdistance`), the paper's profiles keep their own PL0.

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

import numpy as np
from pydantic import BaseModel, ConfigDict, Field, model_validator

from ..geometry import LinkGeometry, PathLossResult
from .base import DEFAULT_FC_GHZ, PathLossOptions, PathLossSpec
from .freespace import free_space_loss_db
from .registry import register


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
    samples_los = False

    @property
    def carrier_shift_db(self) -> float:
        fc = self.profile.fc_ghz if self.fc_ghz is None else self.fc_ghz
        return float(20.0 * np.log10(fc / self.profile.fc_ghz))

    def loss_at_db(self, d3d_m, h_m) -> np.ndarray:
        n, pl0, _ = self.profile.at(h_m)
        d = np.maximum(np.asarray(d3d_m, dtype=float), self.profile.d0_m)
        return pl0 + self.carrier_shift_db + 10.0 * n * np.log10(d / self.profile.d0_m)

    def sigma_db(self, h_m) -> np.ndarray:
        return self.profile.at(h_m)[2]

    def loss_db(self, geom: LinkGeometry) -> np.ndarray:
        return self.loss_at_db(geom.d3d_m, geom.h_air_m)

    def evaluate(self, geom: LinkGeometry, los_uniform: np.ndarray | None = None) -> PathLossResult:
        return PathLossResult(self.loss_db(geom), self.sigma_db(geom.h_air_m), None)


def _build(o: PathLossOptions) -> LogDistance:
    return LogDistance(get_profile(o.profile), o.fc_ghz)  # fc None: the profile's own carrier


register(PathLossSpec(
    name="logdist", model=LogDistance,
    standard="close-in log-distance (Rappaport et al. 2015; Sun et al. 2016) with n, PL0, sigma per altitude "
             "(uavcas paper tab:pathloss_params, or a calibrated profile) and a Friis carrier anchor",
    summary="log-distance per altitude (the twin's profile: calibrated by default)",
    build=_build,
    fit="uavcas.calibration.layer1_fit:fit_logdistance",
))

__all__ = ["PAPER_ANCHORED_PROFILE", "PAPER_RELATIVE_PROFILE", "PROFILES", "LogDistance", "PathLossProfile",
           "get_profile"]


