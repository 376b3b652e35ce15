"""Hover-transit (data-mule / inspection): a closed tour of waypoints at a fixed altitude,
hovering `hover_s` at each and flying straight legs at `speed_mps` in between.

The timeline of one tour is a piecewise-linear map time -> position with knots at the start
and end of every hover, so a position is two `np.interp` calls; the tour repeats forever and
each UAV starts at a seeded phase in it.
"""

from __future__ import annotations

import numpy as np

from uavcas.mobility.area import Area
from uavcas.mobility.base import MissionBase, SeedLike, anchor_box, as_seed_sequence, seeded_anchors
from uavcas.mobility.params import HoverTransitParams


def tour_timeline(waypoints_m: np.ndarray, speed_mps: float, hover_s: float) -> tuple[np.ndarray, np.ndarray]:
    """Knot times (K,) and positions (K, 2) of one closed tour starting with a hover at the first
    waypoint; the last knot equals the first position (arrival back at the start)."""
    w = np.asarray(waypoints_m, dtype=float)
    nxt = np.roll(w, -1, axis=0)
    legs_s = np.linalg.norm(nxt - w, axis=1) / speed_mps
    times, points, t = [], [], 0.0
    for i in range(len(w)):
        times += [t, t + hover_s]
        points += [w[i], w[i]]
        t += hover_s + legs_s[i]
    times.append(t)
    points.append(w[0])
    return np.asarray(times), np.asarray(points)


class HoverTransitMission(MissionBase):
    kind = "hover_transit"

    def __init__(self, n_uav: int, params: HoverTransitParams | None = None, area: Area | None = None, seed: SeedLike = 0):
        if n_uav < 1:
            raise ValueError(f"n_uav must be >= 1, got {n_uav}")
        self.n_uav = int(n_uav)
        self.params = p = params or HoverTransitParams()
        self.area = area or Area()
        self.altitude_m = self.area.clamp_altitude(p.altitude_m)
        anchors_ss, wp_ss, phase_ss = as_seed_sequence(seed).spawn(3)
        size = np.array([self.area.x_max_m, self.area.y_max_m])

        if p.waypoints_m is not None:
            shared = np.clip(np.asarray(p.waypoints_m, dtype=float), 0.0, size)
            tours = [shared] * self.n_uav
        else:
            radius = float(min(p.leg_radius_m, size.min() / 2.0 - p.margin_m))
            radius = max(radius, 0.0)
            lo, hi = anchor_box(self.area, radius, p.margin_m)
            anchors = seeded_anchors(np.random.default_rng(anchors_ss), self.n_uav, lo, hi, p.min_separation_m)
            rng = np.random.default_rng(wp_ss)
            # Waypoints uniform in the disc of `radius` around the anchor (sqrt for uniform area),
            # so legs are a few tens to a couple of hundred metres: transits of seconds to tens
            # of seconds at ~10 m/s, comparable with the hovers within a 60 s run.
            rad = radius * np.sqrt(rng.random((self.n_uav, p.n_waypoints)))
            ang = rng.random((self.n_uav, p.n_waypoints)) * 2.0 * np.pi
            pts = anchors[:, None, :] + np.stack([rad * np.cos(ang), rad * np.sin(ang)], axis=-1)
            tours = [np.clip(pts[i], 0.0, size) for i in range(self.n_uav)]
        self.waypoints_m = tours
        self._timelines = [tour_timeline(w, p.speed_mps, p.hover_s) for w in tours]
        self.period_s = np.array([tl[0][-1] for tl in self._timelines])
        self.phase_s = np.random.default_rng(phase_ss).random(self.n_uav) * self.period_s

    def _positions(self, t: np.ndarray) -> np.ndarray:
        out = np.empty((t.size, self.n_uav, 3))
        for i, (kt, kp) in enumerate(self._timelines):
            tau = np.mod(self.phase_s[i] + t, self.period_s[i]) if self.period_s[i] > 0 else np.zeros_like(t)
            out[:, i, 0] = np.interp(tau, kt, kp[:, 0])
            out[:, i, 1] = np.interp(tau, kt, kp[:, 1])
        out[..., 2] = self.altitude_m
        return out

    def is_hovering(self, t_s: float | np.ndarray) -> np.ndarray:
        """Boolean (T, n_uav) (or (n_uav,) for a scalar): True while the UAV hovers at a waypoint."""
        t = np.atleast_1d(np.asarray(t_s, dtype=float))
        out = np.empty((t.size, self.n_uav), dtype=bool)
        h = self.params.hover_s
        for i, (kt, _) in enumerate(self._timelines):
            tau = np.mod(self.phase_s[i] + t, self.period_s[i]) if self.period_s[i] > 0 else np.zeros_like(t)
            starts = kt[:-1:2]  # hover k occupies [starts[k], starts[k] + h)
            k = np.searchsorted(starts, tau, side="right") - 1
            out[:, i] = (k >= 0) & (tau < starts[np.maximum(k, 0)] + h)
        return out[0] if np.ndim(t_s) == 0 else out
