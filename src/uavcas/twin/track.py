"""A UAV's flight between the plan's windows ("the plan's track"), and where it is on Earth.

The plan gives each UAV's position (x, y, z metres) at every window start `t_s`. The track
interpolates linearly in time between consecutive window starts and holds the last position
after the last start, so the velocity is constant within a window: the forward difference of
the interpolated track over that window, (p[k+1] - p[k]) / (t[k+1] - t[k]), and zero after the
last start. Heading (compass degrees, 0 = north, clockwise) and ground speed follow from the
horizontal velocity; a UAV at rest keeps the heading of its last move (north if it never moved).

Geodesy: the plan's area is a local tangent plane at the plan's `Site` (x east, y north, z up).
A point maps to latitude/longitude with the WGS-84 (NIMA TR8350.2, 3rd ed.) radii of curvature
at the site's latitude: meridian M = a(1-e^2)/(1-e^2 sin^2 phi)^1.5 and prime vertical
N = a/(1-e^2 sin^2 phi)^0.5; dlat = y/(M+h), dlon = x/((N+h) cos phi). Against the exact
ENU -> ECEF -> geodetic conversion it errs by at most 0.12 m across a 1 km x 1 km area at the LW1
site (tests/twin/test_track.py measures it), well below GPS accuracy; the inverse
(`geodetic_to_local`) is the exact inverse of this map, so a round trip is lossless.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from .model import Plan, Site

WGS84_A_M = 6378137.0  # semi-major axis (WGS-84)
WGS84_F = 1 / 298.257223563  # flattening (WGS-84)
WGS84_E2 = WGS84_F * (2 - WGS84_F)  # first eccentricity squared


def _radii_m(site: Site) -> tuple[float, float]:
    """(meridian, prime vertical) radii of curvature at the site, plus its altitude."""
    s = math.sin(math.radians(site.lat_deg))
    w = 1 - WGS84_E2 * s * s
    return WGS84_A_M * (1 - WGS84_E2) / w**1.5 + site.alt_m, WGS84_A_M / math.sqrt(w) + site.alt_m


def local_to_geodetic(site: Site, x_m: float, y_m: float, z_m: float) -> tuple[float, float, float]:
    """(x east, y north, z up) metres from the site -> (lat deg, lon deg, alt m above the ellipsoid)."""
    m, n = _radii_m(site)
    lat = site.lat_deg + math.degrees(y_m / m)
    lon = site.lon_deg + math.degrees(x_m / (n * math.cos(math.radians(site.lat_deg))))
    return lat, lon, site.alt_m + z_m


def geodetic_to_local(site: Site, lat_deg: float, lon_deg: float, alt_m: float) -> tuple[float, float, float]:
    """The exact inverse of `local_to_geodetic`."""
    m, n = _radii_m(site)
    y = math.radians(lat_deg - site.lat_deg) * m
    x = math.radians(lon_deg - site.lon_deg) * n * math.cos(math.radians(site.lat_deg))
    return x, y, alt_m - site.alt_m


@dataclass(frozen=True)
class TrackPoint:
    t_s: float  # plan time
    x_m: float
    y_m: float
    z_m: float
    vx_mps: float  # east
    vy_mps: float  # north
    vz_mps: float  # up
    heading_deg: float  # compass, [0, 360)

    @property
    def groundspeed_mps(self) -> float:
        return math.hypot(self.vx_mps, self.vy_mps)


@dataclass(frozen=True)
class Track:
    """One UAV's window-start samples: times (s) and positions (m)."""

    times_s: tuple[float, ...]
    positions_m: tuple[tuple[float, float, float], ...]

    @classmethod
    def of(cls, plan: Plan, uav: str) -> "Track":
        if not plan.windows:
            raise ValueError("the plan has no windows")
        missing = [w.index for w in plan.windows if uav not in w.positions]
        if missing:
            raise ValueError(f"{uav} has no planned position in window(s) {missing}")
        return cls(tuple(w.t_s for w in plan.windows), tuple(tuple(w.positions[uav]) for w in plan.windows))

    def _segment(self, t_s: float) -> int:
        """Index k of the window start at or before t (0 before the first)."""
        k = 0
        for i, t in enumerate(self.times_s):
            if t <= t_s:
                k = i
        return k

    def _velocity(self, k: int) -> tuple[float, float, float]:
        if k + 1 >= len(self.times_s):
            return 0.0, 0.0, 0.0  # held after the last window start
        dt = self.times_s[k + 1] - self.times_s[k]
        a, b = self.positions_m[k], self.positions_m[k + 1]
        return tuple((b[i] - a[i]) / dt for i in range(3))  # type: ignore[return-value]

    def at(self, t_s: float) -> TrackPoint:
        k = self._segment(t_s)
        v = self._velocity(k)
        a = self.positions_m[k]
        # inside segment k (clamped: before the first start the track is at its first position)
        dt = max(t_s - self.times_s[k], 0.0) if k + 1 < len(self.times_s) else 0.0
        heading = 0.0
        for j in range(k, -1, -1):  # at rest: the heading of the last move
            vj = self._velocity(j)
            if math.hypot(vj[0], vj[1]) > 1e-9:
                heading = math.degrees(math.atan2(vj[0], vj[1])) % 360.0
                break
        return TrackPoint(t_s, a[0] + v[0] * dt, a[1] + v[1] * dt, a[2] + v[2] * dt, v[0], v[1], v[2], heading)

    def speed_in_window_mps(self, k: int) -> float:
        """Planned ground speed during window k (what the GCS commands at its start)."""
        v = self._velocity(k)
        return math.hypot(v[0], v[1])
