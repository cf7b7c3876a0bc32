"""Space environment along the orbit (attitude-independent): Sun, shadow, air density, geomagnetic field.

Simple models, each stated with its source, enough for disturbance torques of 1e-5…1e-3 N·m:
* Sun: low-precision solar ephemeris of the Astronomical Almanac (Vallado, Fundamentals of
  Astrodynamics, 4th ed., Alg. 29; ~0.01° accuracy), mean equator/equinox of date ≈ our ECI.
* Shadow: cylindrical Earth shadow (Vallado Alg. 34 without penumbra).
* Density: exponential atmosphere with the Vallado table 8-4 base altitudes, densities and scale
  heights (CIRA-72, mean solar activity).
* Geomagnetic field: centred tilted dipole, IGRF-12 first-degree coefficients for 2015.0
  (g10 = −29442.0, g11 = −1501.0, h11 = 4797.1 nT), fixed in ECEF and rotated by GMST.
"""
from __future__ import annotations

import numpy as np

from host.core.constants import DEG, WGS84_A
from host.plant.earth import earth_rate_vector, ecef_to_eci
from host.core.frames import L_oi
from host.core.timebase import J2000_JD, julian_date

AU = 149597870700.0            # m
SOLAR_PRESSURE = 4.56e-6       # N/m^2, solar flux 1367 W/m^2 / c at 1 AU
EARTH_RADIUS_DIPOLE = 6371.2e3  # m, IGRF reference radius

# Vallado table 8-4: (base altitude km, nominal density kg/m^3, scale height km)
_EXPONENTIAL_ATMOSPHERE = np.array([
    (0, 1.225, 7.249), (25, 3.899e-2, 6.349), (30, 1.774e-2, 6.682), (40, 3.972e-3, 7.554),
    (50, 1.057e-3, 8.382), (60, 3.206e-4, 7.714), (70, 8.770e-5, 6.549), (80, 1.905e-5, 5.799),
    (90, 3.396e-6, 5.382), (100, 5.297e-7, 5.877), (110, 9.661e-8, 7.263), (120, 2.438e-8, 9.473),
    (130, 8.484e-9, 12.636), (140, 3.845e-9, 16.149), (150, 2.070e-9, 22.523),
    (180, 5.464e-10, 29.740), (200, 2.789e-10, 37.105), (250, 7.248e-11, 45.546),
    (300, 2.418e-11, 53.628), (350, 9.518e-12, 53.298), (400, 3.725e-12, 58.515),
    (450, 1.585e-12, 60.828), (500, 6.967e-13, 63.822), (600, 1.454e-13, 71.835),
    (700, 3.614e-14, 88.667), (800, 1.170e-14, 124.64), (900, 5.245e-15, 181.05),
    (1000, 3.019e-15, 268.00),
])

# IGRF-12, epoch 2015.0, degree 1 (nT): the dipole vector m = [g11, h11, g10] in ECEF
IGRF2015_DIPOLE_NT = np.array([-1501.0, 4797.1, -29442.0])


def sun_position_eci(jd_days, sec_of_day) -> np.ndarray:
    """Geocentric Sun position [m] (…,3), Astronomical Almanac low-precision formulae."""
    T = (julian_date(jd_days, sec_of_day) - J2000_JD) / 36525.0
    mean_lon = (280.460 + 36000.771 * T) * DEG
    M = (357.5291092 + 35999.05034 * T) * DEG
    ecl_lon = mean_lon + (1.914666471 * np.sin(M) + 0.019994643 * np.sin(2 * M)) * DEG
    r = (1.000140612 - 0.016708617 * np.cos(M) - 0.000139589 * np.cos(2 * M)) * AU
    eps = (23.439291 - 0.0130042 * T) * DEG
    return np.stack([r * np.cos(ecl_lon), r * np.cos(eps) * np.sin(ecl_lon),
                     r * np.sin(eps) * np.sin(ecl_lon)], -1)


def sunlit_fraction(R_s, r_sun) -> np.ndarray:
    """1 in sunlight, 0 inside the cylindrical shadow behind the Earth."""
    R_s, r_sun = np.asarray(R_s, float), np.asarray(r_sun, float)
    s_hat = r_sun / np.linalg.norm(r_sun, axis=-1, keepdims=True)
    along = np.sum(R_s * s_hat, -1)
    perp = np.linalg.norm(R_s - along[..., None] * s_hat, axis=-1)
    return np.where((along < 0) & (perp < WGS84_A), 0.0, 1.0)


def atmosphere_band(altitude_m):
    """(base altitude [m], density there [kg/m^3], scale height [m]) of the table row that holds altitude_m."""
    h_km = np.asarray(altitude_m, float) / 1e3
    rows = _EXPONENTIAL_ATMOSPHERE
    i = np.clip(np.searchsorted(rows[:, 0], h_km, side="right") - 1, 0, len(rows) - 1)
    return rows[i, 0] * 1e3, rows[i, 1], rows[i, 2] * 1e3


def air_density(altitude_m) -> np.ndarray:
    """Exponential atmosphere [kg/m^3] at geodetic-ish altitude (above a spherical WGS84_A)."""
    h0, rho0, H = atmosphere_band(altitude_m)
    return rho0 * np.exp(-(np.asarray(altitude_m, float) - h0) / H)


def velocity_relative_to_air(R_s, V_s, jd_days, sec_of_day) -> np.ndarray:
    """ECI velocity w.r.t. an atmosphere co-rotating with the Earth: V − ω_E × R."""
    return np.asarray(V_s, float) - np.cross(earth_rate_vector(jd_days, sec_of_day), R_s)


def magnetic_field_eci(R_s, jd_days, sec_of_day) -> np.ndarray:
    """Tilted-dipole geomagnetic field [T] in ECI: B = (a/r)^3 [3(m·r̂)r̂ − m]."""
    m = ecef_to_eci(IGRF2015_DIPOLE_NT, jd_days, sec_of_day) * 1e-9
    R_s = np.asarray(R_s, float)
    r = np.linalg.norm(R_s, axis=-1, keepdims=True)
    r_hat = R_s / r
    m_dot_r = np.sum(m * r_hat, -1, keepdims=True)
    return (EARTH_RADIUS_DIPOLE / r) ** 3 * (3.0 * m_dot_r * r_hat - m)


class EnvironmentTrack:
    """The orbit and its environment sampled on a time grid, shared by every target of a run.

    Arrays (n, …): t [s from epoch], jd_days, sec_of_day, R [m], V [m/s] (ECI), sun_dir (unit,
    ECI), sunlit (0/1), rho [kg/m^3], v_rel [m/s, ECI, w.r.t. the co-rotating air], B [T, ECI],
    L_oi (n, 3, 3) the orbital frame.
    """

    def __init__(self, t, jd_days, sec_of_day, orbit_states):
        self.t = np.asarray(t, float)
        self.jd_days = np.asarray(jd_days)
        self.sec_of_day = np.asarray(sec_of_day, float)
        self.R = np.ascontiguousarray(orbit_states[:, :3])
        self.V = np.ascontiguousarray(orbit_states[:, 3:])
        self.L_oi = L_oi(self.R, self.V)
        r_sun = sun_position_eci(self.jd_days, self.sec_of_day)
        self.sun_dir = r_sun / np.linalg.norm(r_sun, axis=-1, keepdims=True)
        self.sunlit = sunlit_fraction(self.R, r_sun)
        self.rho = air_density(np.linalg.norm(self.R, axis=-1) - WGS84_A)
        self.v_rel = velocity_relative_to_air(self.R, self.V, self.jd_days, self.sec_of_day)
        self.B = magnetic_field_eci(self.R, self.jd_days, self.sec_of_day)

    def __len__(self) -> int:
        return len(self.t)
