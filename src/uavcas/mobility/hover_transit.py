"""Hover-transit (data-mule / inspection): a closed tour of waypoints at a fixed altitude,
hovering `hover_s` at each and flying straight legs in between (leg by leg,
`uavcas.mobility.legs`: per-leg speeds, acceleration limit, altitude spread).

The tour repeats for ever; each UAV starts at a seeded waypoint of its own tour.
"""

from __future__ import annotations

import numpy as np

from uavcas import seeding
from uavcas.mobility.area import Area
from uavcas.mobility.base import MissionBase, anchor_box, seeded_anchors
from uavcas.mobility.legs import LegFlight, loop
from uavcas.mobility.params import HoverTransitParams


class HoverTransitMission(MissionBase):
    kind = "hover_transit"

    def __init__(self, n_uav: int, params: HoverTransitParams | None = None, area: Area | None = None,
                 seed: seeding.SeedLike = 0):
        if n_uav < 1:
            raise ValueError(f"n_uav must be >= 1, got {n_uav}")
        self.n_uav = int(n_uav)
        self.params = p = params or HoverTransitParams()
        self.area = area or Area()
        self.altitude_m = self.area.clamp_altitude(p.altitude_m)
        anchors_ss, wp_ss, phase_ss, *uav_ss = seeding.as_seed_sequence(seed).spawn(3 + self.n_uav)
        size = np.array([self.area.x_max_m, self.area.y_max_m])

        if p.waypoints_m is not None:
            shared = np.clip(np.asarray(p.waypoints_m, dtype=float), 0.0, size)
            tours = [shared] * self.n_uav
        else:
            radius = float(min(p.leg_radius_m, size.min() / 2.0 - p.margin_m))
            radius = max(radius, 0.0)
            lo, hi = anchor_box(self.area, radius, p.margin_m)
            anchors = seeded_anchors(seeding.generator(anchors_ss), self.n_uav, lo, hi, p.min_separation_m)
            rng = seeding.generator(wp_ss)
            # Waypoints uniform in the disc of `radius` around the anchor (sqrt for uniform area).
            rad = radius * np.sqrt(rng.random((self.n_uav, p.n_waypoints)))
            ang = rng.random((self.n_uav, p.n_waypoints)) * 2.0 * np.pi
            pts = anchors[:, None, :] + np.stack([rad * np.cos(ang), rad * np.sin(ang)], axis=-1)
            tours = [np.clip(pts[i], 0.0, size) for i in range(self.n_uav)]
        self.waypoints_m = tours
        starts = seeding.generator(phase_ss).integers(0, [len(w) for w in tours])
        self.flights = [
            LegFlight(loop(w, int(starts[i])), seeding.generator(uav_ss[i]), speed_mps=p.speed_mps,
                      speed_cv=p.speed_cv, accel_mps2=p.accel_mps2, hover_s=p.hover_s, altitude_m=self.altitude_m,
                      altitude_sd_m=p.altitude_sd_m, altitude_band=(self.area.z_min_m, self.area.z_max_m))
            for i, w in enumerate(tours)
        ]

    def _positions(self, t: np.ndarray) -> np.ndarray:
        return np.stack([f.positions(t) for f in self.flights], axis=1)

    def is_hovering(self, t_s: float | np.ndarray) -> np.ndarray:
        """Boolean (T, n_uav) (or (n_uav,) for a scalar): True while the UAV hovers at a waypoint."""
        t = np.atleast_1d(np.asarray(t_s, dtype=float))
        self.positions(t)  # extends every timeline far enough
        out = np.empty((t.size, self.n_uav), dtype=bool)
        for i, f in enumerate(self.flights):
            k = np.minimum(np.searchsorted(f.t_end, t, side="right"), f.t_end.size - 1)
            out[:, i] = t < f.t_start[k] + f.hover_s
        return out[0] if np.ndim(t_s) == 0 else out
