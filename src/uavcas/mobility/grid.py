"""Boustrophedon (lawn-mower) coverage of a bounding box at fixed altitude, flown leg by leg.

Lanes run parallel to one side of the box, `lane_spacing_m` apart, joined at alternate ends;
the UAV flies the sweep and then flies it back in reverse, for ever, so it never leaves the
box. Speeds, accelerations and altitude per leg: `uavcas.mobility.legs` (the paper's constant
speed is speed_cv 0 without an acceleration limit). Either every UAV sweeps its own box around
a seeded anchor, or all share `box_m` with stratified starting points so they spread out.
"""

from __future__ import annotations

import numpy as np

from uavcas import seeding
from uavcas.mobility.area import Area
from uavcas.mobility.base import MissionBase, anchor_box, seeded_anchors
from uavcas.mobility.legs import LegFlight, back_and_forth
from uavcas.mobility.params import GridParams


def boustrophedon(x0: float, y0: float, x1: float, y1: float, spacing_m: float, along_x: bool = True) -> np.ndarray:
    """Vertices (V, 2) of a lawn-mower sweep of [x0,x1] x [y0,y1] with lanes along x (or y)."""
    if not along_x:
        return boustrophedon(y0, x0, y1, x1, spacing_m, True)[:, ::-1].copy()
    n_lanes = int(np.floor((y1 - y0) / spacing_m + 1e-9)) + 1
    ys = y0 + spacing_m * np.arange(n_lanes)
    verts = []
    for k, y in enumerate(ys):
        a, b = (x0, x1) if k % 2 == 0 else (x1, x0)
        verts += [(a, y), (b, y)]
    return np.asarray(verts, dtype=float)


class GridMission(MissionBase):
    kind = "grid"

    def __init__(self, n_uav: int, params: GridParams | None = None, area: Area | None = None,
                 seed: seeding.SeedLike = 0):
        if n_uav < 1:
            raise ValueError(f"n_uav must be >= 1, got {n_uav}")
        self.n_uav = int(n_uav)
        self.params = p = params or GridParams()
        self.area = area or Area()
        self.altitude_m = self.area.clamp_altitude(p.altitude_m)
        anchors_ss, phase_ss, *uav_ss = seeding.as_seed_sequence(seed).spawn(2 + self.n_uav)
        rng = seeding.generator(phase_ss)
        along_x = rng.random(self.n_uav) < 0.5  # lane orientation per UAV, for variety
        size = np.array([self.area.x_max_m, self.area.y_max_m])

        if p.box_m is not None:
            # A shared box (e.g. fitted from a flight): clipped to the area, never refused.
            lo = np.clip(np.array(p.box_m[:2]), 0.0, size)
            hi = np.clip(np.array(p.box_m[2:]), 0.0, size)
            boxes = np.tile(np.concatenate([lo, hi]), (self.n_uav, 1))
        else:
            half = np.minimum(np.array([p.box_width_m, p.box_height_m]) / 2.0, size / 2.0 - p.margin_m)
            half = np.maximum(half, 0.0)
            alo, ahi = anchor_box(self.area, float(half.max()), p.margin_m)
            centres = seeded_anchors(seeding.generator(anchors_ss), self.n_uav, alo, ahi, p.min_separation_m)
            boxes = np.concatenate([np.maximum(centres - half, 0.0), np.minimum(centres + half, size)], axis=1)
        self.boxes_m = boxes
        self.paths = [boustrophedon(*boxes[i], p.lane_spacing_m, bool(along_x[i])) for i in range(self.n_uav)]
        # Stratified starts over the out-and-back: with a shared box, UAV i starts in the i-th of
        # n equal slices of the sweep's vertices (random order).
        order = rng.permutation(self.n_uav)
        self.flights = []
        for i, path in enumerate(self.paths):
            n_cycle = max(2 * len(path) - 2, 1)
            start = int((order[i] + rng.random()) / self.n_uav * n_cycle) % n_cycle
            self.flights.append(LegFlight(
                back_and_forth(path, start), seeding.generator(uav_ss[i]), speed_mps=p.speed_mps,
                speed_cv=p.speed_cv, accel_mps2=p.accel_mps2, altitude_m=self.altitude_m,
                altitude_sd_m=p.altitude_sd_m, altitude_band=(self.area.z_min_m, self.area.z_max_m)))

    def _positions(self, t: np.ndarray) -> np.ndarray:
        return np.stack([f.positions(t) for f in self.flights], axis=1)
