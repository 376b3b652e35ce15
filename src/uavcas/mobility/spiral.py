"""Archimedean spiral search at fixed altitude and constant ground speed.

r(theta) = r0 + b * theta with b = pitch / (2 pi), so consecutive loops are `pitch` metres apart.
Constant *ground* speed means the arc length s grows linearly in time; the arc length of an
Archimedean spiral has a closed form in r,
    S(r) = F(r) - F(r0),   F(u) = [u sqrt(u^2 + b^2) + b^2 asinh(u / b)] / (2 b),
which we invert by table interpolation refined with one Newton step (dS/dr = sqrt(r^2+b^2)/b).
The UAV ping-pongs between r0 and r_max so it never leaves its disc.
"""

from __future__ import annotations

import numpy as np

from uavcas.mobility.area import Area
from uavcas.mobility.base import MissionBase, SeedLike, anchor_box, as_seed_sequence, ping_pong, seeded_anchors
from uavcas.mobility.params import SpiralParams

_TABLE_POINTS = 2048


def _arc_primitive(u: np.ndarray, b: float) -> np.ndarray:
    return (u * np.sqrt(u * u + b * b) + b * b * np.arcsinh(u / b)) / (2.0 * b)


class SpiralMission(MissionBase):
    kind = "spiral"

    def __init__(self, n_uav: int, params: SpiralParams | None = None, area: Area | None = None, seed: SeedLike = 0):
        if n_uav < 1:
            raise ValueError(f"n_uav must be >= 1, got {n_uav}")
        self.n_uav = int(n_uav)
        self.params = params or SpiralParams()
        self.area = area or Area()
        p = self.params
        self.altitude_m = self.area.clamp_altitude(p.altitude_m)
        # The disc must fit in the area with the margin; a too-large r_max is shrunk, not refused,
        # so a profile fitted on a big field still runs in a small area.
        half = min(self.area.x_max_m, self.area.y_max_m) / 2.0 - p.margin_m
        self.r_max_m = float(min(p.r_max_m, max(half, p.r0_m + 1e-6)))
        self.r0_m = float(min(p.r0_m, self.r_max_m))
        self.b_m = p.pitch_m / (2.0 * np.pi)
        self.length_m = float(self._arc(np.array([self.r_max_m]))[0])
        r_tab = np.linspace(self.r0_m, self.r_max_m, _TABLE_POINTS)
        self._r_tab, self._s_tab = r_tab, self._arc(r_tab)

        anchors_ss, phase_ss = as_seed_sequence(seed).spawn(2)
        lo, hi = anchor_box(self.area, self.r_max_m, p.margin_m)
        self.centres_m = seeded_anchors(np.random.default_rng(anchors_ss), self.n_uav, lo, hi, p.min_separation_m)
        rng = np.random.default_rng(phase_ss)
        # Per-UAV phase: where on the out-and-back arc it starts, which way it turns, and the
        # spiral's angular origin, so UAVs sharing parameters do not fly in lockstep.
        self.s0_m = rng.random(self.n_uav) * 2.0 * self.length_m
        self.turn = np.where(rng.random(self.n_uav) < 0.5, -1.0, 1.0)
        self.theta0_rad = rng.random(self.n_uav) * 2.0 * np.pi

    def _arc(self, r: np.ndarray) -> np.ndarray:
        return _arc_primitive(r, self.b_m) - _arc_primitive(np.array(self.r0_m), self.b_m)

    def radius_at_arc(self, s_m: np.ndarray) -> np.ndarray:
        """Invert S(r) = s for s in [0, length_m]."""
        r = np.interp(s_m, self._s_tab, self._r_tab)
        r = r - (self._arc(r) - s_m) * self.b_m / np.sqrt(r * r + self.b_m**2)
        return np.clip(r, self.r0_m, self.r_max_m)

    def _positions(self, t: np.ndarray) -> np.ndarray:
        s = ping_pong(self.s0_m[None, :] + self.params.speed_mps * t[:, None], self.length_m)  # (T, n)
        r = self.radius_at_arc(s)
        theta = self.theta0_rad[None, :] + self.turn[None, :] * (r - self.r0_m) / self.b_m
        out = np.empty((t.size, self.n_uav, 3))
        out[..., 0] = self.centres_m[None, :, 0] + r * np.cos(theta)
        out[..., 1] = self.centres_m[None, :, 1] + r * np.sin(theta)
        out[..., 2] = self.altitude_m
        return out
