"""Two-ray ground reflection: the direct ray and one ray reflected by flat ground, coherently
summed with the Fresnel reflection coefficient (Rappaport, Wireless Communications, 2nd ed.,
secs. 4.5-4.6; ground constants from ITU-R P.527). Calibration fits its ground and the antennas'
amplitude ratio (`uavcas.calibration.layer1_fit.fit_two_ray`).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

import numpy as np
from scipy.constants import c as SPEED_OF_LIGHT_M_S

from ..geometry import MIN_DISTANCE_M, LinkGeometry, PathLossResult
from .base import DEFAULT_FC_GHZ, PathLossSpec
from .registry import register


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
    samples_los = False

    def reflection_coefficient(self, sin_psi) -> np.ndarray:
        lam = SPEED_OF_LIGHT_M_S / (self.fc_ghz * 1e9)
        eps = self.eps_r - 1j * 60.0 * self.conductivity_s_m * lam
        s = np.asarray(sin_psi, dtype=float)
        root = np.sqrt(eps - (1.0 - s**2))
        if self.polarisation == "vertical":
            return (eps * s - root) / (eps * s + root)
        return (s - root) / (s + root)

    def loss_at_db(self, d2d_m, h_tx_m, h_rx_m) -> np.ndarray:
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

    def loss_db(self, geom: LinkGeometry) -> np.ndarray:
        return self.loss_at_db(geom.d2d_m, geom.h_ground_m, geom.h_air_m)

    def evaluate(self, geom: LinkGeometry, los_uniform: np.ndarray | None = None) -> PathLossResult:
        loss = self.loss_db(geom)
        return PathLossResult(loss, np.full(loss.shape, self.sigma_db), None)


register(PathLossSpec(
    name="tworay", model=TwoRay,
    standard="two-ray ground reflection, Rappaport, Wireless Communications 2nd ed. secs. 4.5-4.6 (Fresnel "
             "coefficient, vertical polarisation), ground ITU-R P.527 medium dry (eps_r 15, 1e-3 S/m)",
    summary="two-ray ground reflection over flat ground, deterministic",
    build=lambda o: TwoRay(fc_ghz=o.carrier_ghz),
    fit="uavcas.calibration.layer1_fit:fit_two_ray",
))

__all__ = ["TwoRay"]
