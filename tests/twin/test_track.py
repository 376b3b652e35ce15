"""The plan's site, system ids and track (uavcas.twin.track): pure, no root."""

from __future__ import annotations

import math

import pytest

from uavcas.twin import Site
from uavcas.twin.load import plan_from_data, read_plan
from uavcas.twin.model import SCHEMA_VERSION
from uavcas.twin.plan import plan
from uavcas.twin.track import WGS84_A_M, WGS84_E2, Track, geodetic_to_local, local_to_geodetic

CFG = "benign-6-2-telemetry-logdist-adaptive-random-30-95"


def _exact_enu_to_geodetic(site: Site, e: float, n: float, u: float) -> tuple[float, float, float]:
    """ENU -> ECEF -> geodetic (WGS-84, Bowring-style fixed-point iteration): the reference."""
    la, lo = math.radians(site.lat_deg), math.radians(site.lon_deg)
    nn = WGS84_A_M / math.sqrt(1 - WGS84_E2 * math.sin(la) ** 2)
    x0 = (nn + site.alt_m) * math.cos(la) * math.cos(lo)
    y0 = (nn + site.alt_m) * math.cos(la) * math.sin(lo)
    z0 = (nn * (1 - WGS84_E2) + site.alt_m) * math.sin(la)
    x = x0 - math.sin(lo) * e - math.sin(la) * math.cos(lo) * n + math.cos(la) * math.cos(lo) * u
    y = y0 + math.cos(lo) * e - math.sin(la) * math.sin(lo) * n + math.cos(la) * math.sin(lo) * u
    z = z0 + math.cos(la) * n + math.sin(la) * u
    p, lon = math.hypot(x, y), math.atan2(y, x)
    lat = math.atan2(z, p * (1 - WGS84_E2))
    for _ in range(20):
        nn = WGS84_A_M / math.sqrt(1 - WGS84_E2 * math.sin(lat) ** 2)
        h = p / math.cos(lat) - nn
        lat = math.atan2(z, p * (1 - WGS84_E2 * nn / (nn + h)))
    return math.degrees(lat), math.degrees(lon), h


def test_the_plan_records_the_lw1_site_and_mavlink_sysids_bit_for_bit():
    a, b = plan(CFG, seed=14, windows=4), plan(CFG, seed=14, windows=4)
    assert a.to_json() == b.to_json() and read_plan(a.to_json()) == a
    assert a.schema_version == SCHEMA_VERSION == 5 and a.site == Site() and a.site.name == "AERPAW LW1"
    assert (a.site.lat_deg, a.site.lon_deg) == (35.727451, -78.695974)
    assert [n.sysid for n in a.nodes] == [1, 2, 3, 4, 5, 6, 255, 254]
    # a plan.json of schema 1 (no site, no sysids) reads with the same defaults
    old = a.model_dump(mode="json")
    old["schema_version"] = 1
    del old["site"]
    del old["mavlink_stream_hz"]  # schema 5's field: older plans were run at MAVProxy's default
    for n in old["nodes"]:
        del n["sysid"]
    back = plan_from_data(old)
    assert back.site == a.site and [n.sysid for n in back.nodes] == [n.sysid for n in a.nodes]
    assert back.mavlink_stream_hz == 4


def test_too_many_nodes_for_mavlink_ids_is_one_line():
    with pytest.raises(ValueError, match="exceed the 255 MAVLink system ids"):
        plan("benign-250-6-mixed-logdist-adaptive-random-30-95", seed=1, windows=1)


def test_1000_m_north_is_the_hand_computed_latitude_step():
    site = Site()
    # by hand (WGS-84 at 35.727451 deg): sin^2 = 0.340 975, 1 - e^2 sin^2 = 0.997 717;
    # M = a(1-e^2)/0.997 717^1.5 = 6 357 193 m; 1000 m / M = 1.573 020e-4 rad = 0.009 012 7 deg.
    # (the spherical 6371 km Earth would say 0.008 993 deg: 0.2 % short at this latitude)
    lat, lon, alt = local_to_geodetic(site, 0.0, 1000.0, 50.0)
    assert lat - site.lat_deg == pytest.approx(0.0090127, abs=2e-7)
    assert lon == site.lon_deg and alt == 50.0
    # east: N cos phi = a/0.997 717^0.5 * 0.811 804 = 6 385 429 * 0.811 804 = 5 183 716 m per rad
    # -> 0.011 053 0 deg per km
    _, lon_e, _ = local_to_geodetic(site, 1000.0, 0.0, 0.0)
    assert lon_e - site.lon_deg == pytest.approx(0.0110530, abs=2e-7)


def test_tangent_plane_error_over_the_area_is_decimetres_at_most_and_the_inverse_is_exact():
    site = Site()
    worst = 0.0
    for e, n, u in [(1000.0, 1000.0, 110.0), (1000.0, 0.0, 30.0), (0.0, 1000.0, 70.0), (500.0, 250.0, 90.0)]:
        lat, lon, _ = local_to_geodetic(site, e, n, u)
        rlat, rlon, _ = _exact_enu_to_geodetic(site, e, n, u)
        x, y, _ = geodetic_to_local(site, rlat, rlon, u)
        worst = max(worst, math.hypot(x - e, y - n))
        back = geodetic_to_local(site, lat, lon, u)
        assert back == pytest.approx((e, n, u), abs=1e-6)
    assert 0.0 < worst < 0.15, worst


def test_track_interpolates_between_window_starts_and_holds_after_the_last():
    p = plan(CFG, seed=14, windows=4)
    tr = Track.of(p, "uav2")
    w0, w1, w3 = p.windows[0].positions["uav2"], p.windows[1].positions["uav2"], p.windows[3].positions["uav2"]
    mid = tr.at(p.window_s / 2)
    for i, c in enumerate((mid.x_m, mid.y_m, mid.z_m)):
        assert c == pytest.approx((w0[i] + w1[i]) / 2)
    v = [(w1[i] - w0[i]) / p.window_s for i in range(3)]
    assert (mid.vx_mps, mid.vy_mps, mid.vz_mps) == pytest.approx(v)
    assert mid.groundspeed_mps == pytest.approx(math.hypot(v[0], v[1])) == pytest.approx(tr.speed_in_window_mps(0))
    assert mid.heading_deg == pytest.approx(math.degrees(math.atan2(v[0], v[1])) % 360)
    assert mid.groundspeed_mps > 0.5  # the random mission moves: the check above is not about zeros
    late = tr.at(p.duration_s + 3.0)
    assert (late.x_m, late.y_m, late.z_m) == pytest.approx(w3) and late.groundspeed_mps == 0.0
    assert tr.speed_in_window_mps(3) == 0.0
    assert tr.at(p.windows[2].t_s).x_m == pytest.approx(p.windows[2].positions["uav2"][0])
