"""Rectangular spiral search at fixed altitude, flown leg by leg.

The AFAR "spiral" flights are not Archimedean: they are expanding axis-aligned rectangles
(74-92 % of the moving steps axis-aligned, legs of 10-250 m flown at 1-10 m/s over about
300 x 215 m). The path here is the square spiral scaled to the footprint: from the centre,
legs of 1, 1, 2, 2, 3, 3, ... ring units alternately along x and y, turning the same way,
until the footprint `width_m` x `height_m` is covered (R rings, unit width / 2R along x and
height / 2R along y, R = floor(min(width, height) / (2 ring_spacing)), at least 1); then the
UAV flies it back inwards, and out again (`legs.back_and_forth`). Speeds, accelerations and
altitude per leg: `uavcas.mobility.legs`.

Per UAV (seeded): the centre (anchors at least `min_separation_m` apart), the turning sense,
the footprint orientation (x/y swapped or not) and where in the out-and-back the UAV starts.
"""

from __future__ import annotations

import numpy as np

from uavcas import seeding
from uavcas.mobility.area import Area
from uavcas.mobility.base import MissionBase, anchor_box, seeded_anchors
from uavcas.mobility.legs import LegFlight, back_and_forth
from uavcas.mobility.params import SpiralParams


def rectangular_spiral(width_m: float, height_m: float, ring_spacing_m: float, turn: float = 1.0) -> np.ndarray:
    """Vertices (4R + 1, 2) of the square spiral scaled to width x height, centred on (0, 0)."""
    rings = max(1, int(np.floor(min(width_m, height_m) / (2.0 * ring_spacing_m))))
    ux, uy = width_m / (2.0 * rings), height_m / (2.0 * rings)
    pts = [(0.0, 0.0)]
    x = y = 0.0
    sign = 1.0
    for k in range(1, 2 * rings + 1):
        x += sign * k * ux
        pts.append((x, y))
        y += turn * sign * k * uy
        pts.append((x, y))
        sign = -sign
    v = np.asarray(pts)
    # The spiral is asymmetric about its start; centre its bounding box on (0, 0).
    return v - (v.min(axis=0) + v.max(axis=0)) / 2.0


class SpiralMission(MissionBase):
    kind = "spiral"

    def __init__(self, n_uav: int, params: SpiralParams | None = None, area: Area | None = None,
                 seed: seeding.SeedLike = 0):
        if n_uav < 1:
            raise ValueError(f"n_uav must be >= 1, got {n_uav}")
        self.n_uav = int(n_uav)
        self.params = p = params or SpiralParams()
        self.area = area or Area()
        self.altitude_m = self.area.clamp_altitude(p.altitude_m)
        anchors_ss, shape_ss, *uav_ss = seeding.as_seed_sequence(seed).spawn(2 + self.n_uav)
        rng = seeding.generator(shape_ss)
        swap = rng.random(self.n_uav) < 0.5
        turn = np.where(rng.random(self.n_uav) < 0.5, -1.0, 1.0)
        # The footprint must fit in the area with the margin; a too-large one is shrunk, not refused.
        room = np.array([self.area.x_max_m, self.area.y_max_m]) - 2.0 * p.margin_m
        half = max(p.width_m, p.height_m) / 2.0
        lo, hi = anchor_box(self.area, half, p.margin_m)
        self.centres_m = seeded_anchors(seeding.generator(anchors_ss), self.n_uav, lo, hi, p.min_separation_m)
        self.paths = []
        self.flights = []
        for i in range(self.n_uav):
            w, h = (p.height_m, p.width_m) if swap[i] else (p.width_m, p.height_m)
            w, h = min(w, max(room[0], 1e-6)), min(h, max(room[1], 1e-6))
            path = rectangular_spiral(w, h, p.ring_spacing_m, turn[i]) + self.centres_m[i]
            path = np.clip(path, 0.0, [self.area.x_max_m, self.area.y_max_m])
            self.paths.append(path)
            r = seeding.generator(uav_ss[i])
            start = int(r.integers(0, 2 * len(path) - 2))
            self.flights.append(LegFlight(
                back_and_forth(path, start, bool(r.random() < 0.5)), r, speed_mps=p.speed_mps, speed_cv=p.speed_cv,
                accel_mps2=p.accel_mps2, altitude_m=self.altitude_m, altitude_sd_m=p.altitude_sd_m,
                altitude_band=(self.area.z_min_m, self.area.z_max_m)))

    def _positions(self, t: np.ndarray) -> np.ndarray:
        return np.stack([f.positions(t) for f in self.flights], axis=1)
