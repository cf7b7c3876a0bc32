"""Time base, GMST, WGS-84 geodetic <-> ECEF, ECEF -> ECI and ground-target kinematics."""
import numpy as np

from host.core.constants import EARTH_ROTATION_RATE, WGS84_A
from host.plant.earth import ecef_to_eci, ecef_to_geodetic, geodetic_to_ecef, local_up, target_eci
from host.core.timebase import add_seconds, gmst, gmst_rate, julian_date, utc_to_jd

D = np.pi / 180.0


def test_julian_dates_of_published_epochs():
    assert utc_to_jd(2000, 1, 1, 12) == (2451545, 43200.0)  # J2000.0 = JD 2451545.0
    # Vallado Example 3-4: 1996 Oct 26 14:20:00 UT -> JD 2450383.09722222
    assert abs(julian_date(*utc_to_jd(1996, 10, 26, 14, 20, 0)) - 2450383.09722222) < 1e-8


def test_gmst_vallado_example_3_5():
    # 1992 Aug 20 12:14 UT1 -> GMST = 152.578787810 deg (Vallado, Example 3-5)
    g = gmst(*utc_to_jd(1992, 8, 20, 12, 14, 0)) / D
    assert abs(g - 152.578787810) < 1e-6


def test_gmst_at_j2000_is_the_iau82_constant():
    # Astronomical Almanac: GMST(J2000.0, 2000 Jan 1 12h UT1) = 18h 41m 50.54841s
    g = gmst(*utc_to_jd(2000, 1, 1, 12)) / D
    assert abs(g - (18 + 41 / 60 + 50.54841 / 3600) * 15.0) < 1e-9


def test_gmst_continuous_across_midnight_and_rate_consistent():
    jd, s = utc_to_jd(2017, 5, 31, 23, 59, 50.0)
    t = np.linspace(0.0, 20.0, 21)
    J, S = add_seconds(jd, s, t)
    g = np.unwrap(gmst(J, S))
    np.testing.assert_allclose(np.diff(g), gmst_rate(jd, s) * 1.0, rtol=1e-9)
    # IAU-82 mean sidereal rate 7.2921158553e-5 rad/s (Aoki et al. 1982); WGS-84's nominal
    # 7.292115e-5 is that value rounded (1.2e-7 relative)
    assert abs(gmst_rate(jd, s) / 7.2921158553e-5 - 1.0) < 1e-10
    assert abs(gmst_rate(jd, s) / EARTH_ROTATION_RATE - 1.0) < 1.3e-7


def test_geodetic_to_ecef_vallado_site():
    # Vallado Example 7-1 site: 39.007 N, 104.883 W, h = 2187 m -> [-1275.1219, -4797.9890, 3994.2975] km
    r = geodetic_to_ecef(-104.883 * D, 39.007 * D, 2187.0)
    np.testing.assert_allclose(r, [-1275121.9, -4797989.0, 3994297.5], rtol=0, atol=0.15)


def test_geodetic_points_lie_on_the_ellipsoid_with_the_right_normal():
    rng = np.random.default_rng(1)
    lon, lat = rng.uniform(-np.pi, np.pi, 200), rng.uniform(-np.pi / 2, np.pi / 2, 200)
    a, b = 6378137.0, 6356752.314245  # WGS-84 a and published b
    r = geodetic_to_ecef(lon, lat)
    on_surface = (r[:, 0] ** 2 + r[:, 1] ** 2) / a**2 + r[:, 2] ** 2 / b**2
    np.testing.assert_allclose(on_surface, 1.0, rtol=0, atol=5e-13)  # b is published to 1 um
    grad = r / np.array([a**2, a**2, b**2])  # ellipsoid normal, to compare with the geodetic up
    up = grad / np.linalg.norm(grad, axis=-1, keepdims=True)
    np.testing.assert_allclose(up, local_up(lon, lat), rtol=0, atol=1e-12)
    # a height moves the point along that normal
    np.testing.assert_allclose(geodetic_to_ecef(lon, lat, 1234.5) - r, 1234.5 * up, rtol=0, atol=1e-8)
    np.testing.assert_allclose(geodetic_to_ecef(0.0, 0.0), [a, 0, 0], rtol=0, atol=1e-9)
    np.testing.assert_allclose(geodetic_to_ecef(0.3, np.pi / 2), [0, 0, b], rtol=0, atol=1e-6)


def test_ecef_to_geodetic_round_trip():
    rng = np.random.default_rng(2)
    lon, lat, h = rng.uniform(-np.pi, np.pi, 100), rng.uniform(-1.55, 1.55, 100), rng.uniform(-500, 9e3, 100)
    lo, la, hh = ecef_to_geodetic(geodetic_to_ecef(lon, lat, h))
    np.testing.assert_allclose(lo, lon, rtol=0, atol=1e-14)
    np.testing.assert_allclose(la, lat, rtol=0, atol=1e-13)
    np.testing.assert_allclose(hh, h, rtol=0, atol=1e-6)


def test_eci_target_rotates_with_the_earth():
    jd, s = utc_to_jd(2017, 5, 31, 4, 40, 0)
    lon, lat = 120 * D, 30 * D
    r0, v0, a0 = target_eci(jd, s, lon, lat)
    dt = 100.0
    r1 = target_eci(*add_seconds(jd, s, dt), lon, lat)[0]

    def rz(ang):  # active rotation about z_i
        return np.array([[np.cos(ang), -np.sin(ang), 0], [np.sin(ang), np.cos(ang), 0], [0, 0, 1]])

    w_iau = 7.2921158553e-5  # IAU-82 sidereal rate
    np.testing.assert_allclose(r1, rz(w_iau * dt) @ r0, rtol=0, atol=1e-5)
    # WGS-84 nominal w_E differs by 1.2e-7: 8.6e-10 rad after 100 s, ~5 mm at 5500 km from the axis
    np.testing.assert_allclose(r1, rz(EARTH_ROTATION_RATE * dt) @ r0, rtol=0, atol=1e-2)
    w = np.array([0, 0, w_iau])
    np.testing.assert_allclose(v0, np.cross(w, r0), rtol=0, atol=1e-8)
    np.testing.assert_allclose(a0, np.cross(w, np.cross(w, r0)), rtol=0, atol=1e-12)
    # height and z are not changed by Earth rotation; x-y radius is (N + h) cos(lat)
    np.testing.assert_allclose(np.hypot(r0[0], r0[1]), np.hypot(*geodetic_to_ecef(lon, lat)[:2]), rtol=1e-15)
    # at GMST the ECI longitude of the target is lon + GMST
    assert abs(np.mod(np.arctan2(r0[1], r0[0]) - lon - gmst(jd, s) + np.pi, 2 * np.pi) - np.pi) < 1e-14


def test_ecef_to_eci_preserves_norm_and_z():
    r = np.array([WGS84_A, 1e5, 2e6])
    ri = ecef_to_eci(r, *utc_to_jd(2020, 3, 1, 7, 0, 0))
    assert abs(np.linalg.norm(ri) - np.linalg.norm(r)) < 1e-8 and ri[2] == r[2]
