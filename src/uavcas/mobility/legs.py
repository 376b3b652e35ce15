"""Leg-by-leg flight along a polyline: per-leg cruise speeds, acceleration limit, hovers, altitude.

The AFAR flights (calibration layer 2) are sequences of straight legs: the autopilot flies to a
waypoint, slows down, turns, and flies the next leg at a speed that differs from leg to leg
(rectangular spirals at 1-10 m/s, lawn-mower lanes at ~5 m/s, transits between hovers). Spiral,
grid and hover-transit missions are built on this one engine, and calibration fits its
parameters by simulating it (`uavcas.calibration.layer2_mobility`):

* Legs: the mission gives an endless sequence of vertices (e.g. a path flown forward and back,
  or a closed tour repeated); leg k joins vertex k and k + 1.
* Cruise speed of leg k: v_k ~ lognormal with mean `speed_mps` and coefficient of variation
  `speed_cv` (std / mean; 0: every leg at `speed_mps`), drawn per leg.
* Speed profile: from rest at the leg's start to rest at its end (multirotor waypoint
  navigation stops at each waypoint) with acceleration `accel_mps2`: trapezoidal, or triangular
  with peak sqrt(a L) when the leg is too short to reach v_k; None = instant speed changes
  (constant speed on every leg).
* Hover: `hover_s` seconds at each vertex before the leg (hover-transit); 0 elsewhere.
* Altitude: leg k ends at a_k = altitude + `altitude_sd_m` N(0, 1) (drawn per leg), reached
  linearly along the leg; the mission clamps it into the area's band.

Determinism: each UAV has its own Generator; legs are drawn in order, and the timeline is
extended lazily as far as a query needs, so a position never depends on which times were asked
before (leg k's draws are the k-th draws whatever the query).
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

_CHUNK = 64  # legs added per extension


def lognormal_speeds(rng: np.random.Generator, n: int, mean_mps: float, cv: float) -> np.ndarray:
    """n cruise speeds with the given mean and coefficient of variation (lognormal; cv 0: constant)."""
    if mean_mps <= 0:
        return np.zeros(n)
    if cv <= 0:
        rng.standard_normal(n)  # keep the stream aligned whatever cv is
        return np.full(n, float(mean_mps))
    s2 = np.log1p(cv * cv)
    return mean_mps * np.exp(np.sqrt(s2) * rng.standard_normal(n) - s2 / 2.0)


def leg_duration_s(length_m: np.ndarray, v_mps: np.ndarray, accel_mps2: float | None) -> np.ndarray:
    """Time to fly each leg from rest to rest (trapezoid / triangle), or L / v without a limit."""
    L, v = np.asarray(length_m, float), np.asarray(v_mps, float)
    with np.errstate(divide="ignore", invalid="ignore"):
        if accel_mps2 is None:
            return np.where(L > 0, np.where(v > 0, L / v, np.inf), 0.0)
        a = float(accel_mps2)
        full = L >= v * v / a  # reaches cruise
        return np.where(L <= 0, 0.0, np.where(v <= 0, np.inf, np.where(full, L / v + v / a, 2.0 * np.sqrt(L / a))))


def distance_along_m(tau_s: np.ndarray, length_m: np.ndarray, v_mps: np.ndarray,
                     accel_mps2: float | None) -> np.ndarray:
    """Distance covered tau seconds into a leg (tau within the leg's duration)."""
    tau, L, v = (np.asarray(x, float) for x in (tau_s, length_m, v_mps))
    if accel_mps2 is None:
        return np.minimum(v * tau, L)
    a = float(accel_mps2)
    T = leg_duration_s(L, v, a)
    vp = np.minimum(v, np.sqrt(a * np.maximum(L, 0.0)))  # peak speed (cruise or triangle top)
    t_acc = vp / a
    up = 0.5 * a * tau**2
    cruise = 0.5 * a * t_acc**2 + vp * (tau - t_acc)
    rest = np.maximum(T - tau, 0.0)
    down = L - 0.5 * a * rest**2
    s = np.where(tau < t_acc, up, np.where(tau <= T - t_acc, cruise, down))
    return np.clip(s, 0.0, L)


class LegFlight:
    """One UAV flying the legs of `vertex_source` (k -> (m, 2) next vertices) from t = 0."""

    def __init__(self, vertex_source: Callable[[int], np.ndarray], rng: np.random.Generator, *,
                 speed_mps: float, speed_cv: float = 0.0, accel_mps2: float | None = None,
                 hover_s: float = 0.0, altitude_m: float, altitude_sd_m: float = 0.0,
                 altitude_band: tuple[float, float] | None = None) -> None:
        self._source = vertex_source
        self._rng = rng
        self.speed_mps, self.speed_cv, self.accel_mps2 = float(speed_mps), float(speed_cv), accel_mps2
        self.hover_s = float(hover_s)
        self.altitude_m, self.altitude_sd_m = float(altitude_m), float(altitude_sd_m)
        self._band = altitude_band
        first = np.asarray(vertex_source(0), dtype=float)
        self._vertices = [first[0]]
        self._alt = [self._clamp(self.altitude_m)]
        self._pending = list(first[1:])
        self._calls = 1
        self.t_start = np.zeros(0)  # leg k: hover starts at t_start[k], flight at t_start[k] + hover_s
        self.t_end = np.zeros(0)
        self.length = np.zeros(0)
        self.v = np.zeros(0)

    def _clamp(self, z: float) -> float:
        return float(np.clip(z, *self._band)) if self._band is not None else float(z)

    def _extend(self) -> None:
        while len(self._pending) < _CHUNK:
            self._pending.extend(np.asarray(self._source(self._calls), dtype=float))
            self._calls += 1
        new = np.asarray(self._pending[:_CHUNK])
        del self._pending[:_CHUNK]
        prev = np.vstack([self._vertices[-1][None, :], new])
        length = np.linalg.norm(np.diff(prev, axis=0), axis=1)
        v = lognormal_speeds(self._rng, _CHUNK, self.speed_mps, self.speed_cv)
        alt = self.altitude_m + self.altitude_sd_m * self._rng.standard_normal(_CHUNK)
        dur = self.hover_s + leg_duration_s(length, v, self.accel_mps2)
        t0 = self.t_end[-1] if self.t_end.size else 0.0
        ends = t0 + np.cumsum(dur)
        if ends[-1] <= t0:  # nothing to fly (all vertices in one place): stay there for ever
            ends[-1] = np.inf
        self.t_start = np.r_[self.t_start, t0, ends[:-1]]
        self.t_end = np.r_[self.t_end, ends]
        self.length = np.r_[self.length, length]
        self.v = np.r_[self.v, v]
        self._vertices.extend(new)
        self._alt.extend(self._clamp(z) for z in alt)

    def positions(self, t: np.ndarray) -> np.ndarray:
        """(T, 3) positions at times t >= 0."""
        t = np.asarray(t, dtype=float)
        tmax = float(t.max()) if t.size else 0.0
        while not self.t_end.size or (self.t_end[-1] <= tmax and np.isfinite(self.t_end[-1])):
            self._extend()
        k = np.minimum(np.searchsorted(self.t_end, t, side="right"), self.t_end.size - 1)
        verts = np.asarray(self._vertices)
        alts = np.asarray(self._alt)
        tau = np.maximum(t - self.t_start[k] - self.hover_s, 0.0)
        s = distance_along_m(tau, self.length[k], self.v[k], self.accel_mps2)
        with np.errstate(invalid="ignore", divide="ignore"):
            frac = np.where(self.length[k] > 0, s / self.length[k], 1.0)
        a, b = verts[k], verts[k + 1]
        out = np.empty((t.size, 3))
        out[:, :2] = a + frac[:, None] * (b - a)
        out[:, 2] = alts[k] + frac * (alts[k + 1] - alts[k])
        return out


def back_and_forth(path: np.ndarray, start: int = 0, forward: bool = True) -> Callable[[int], np.ndarray]:
    """Vertex source flying `path` (V, 2) end to end and back, for ever, from vertex `start`
    (an index into the out-and-back cycle), in the path's direction or against it."""
    p = np.asarray(path, dtype=float)
    cycle = np.vstack([p, p[-2:0:-1]]) if len(p) > 2 else p  # one out-and-back, no vertex twice
    if not forward:
        cycle = cycle[::-1]
    lap = np.roll(cycle, -(start % len(cycle)), axis=0)
    return lambda call: lap  # consecutive laps join: lap[-1] -> lap[0] is a leg of the cycle


def loop(tour: np.ndarray, start: int = 0) -> Callable[[int], np.ndarray]:
    """Vertex source flying the closed `tour` (V, 2) round and round from vertex `start`."""
    lap = np.roll(np.asarray(tour, dtype=float), -start, axis=0)
    return lambda call: lap
