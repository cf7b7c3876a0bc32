"""Physical constants of the staring scenario (SI units) and angle-unit helpers.

Values: WGS-84 (NIMA TR8350.2, 3rd ed.): GM (with atmosphere), semi-major axis, flattening and
the nominal mean angular velocity of the Earth. The sidereal rate actually used to rotate targets
is the time derivative of the IAU-82 GMST formula (host.core.timebase.gmst_rate), which differs from
the WGS-84 nominal value by 1.2e-7 relative (7.2921158553e-5 vs 7.292115e-5 rad/s).
"""
from __future__ import annotations

import numpy as np

MU_EARTH = 3.986004418e14            # m^3/s^2, WGS-84 GM
WGS84_A = 6378137.0                  # m, semi-major axis
WGS84_F = 1.0 / 298.257223563        # flattening
WGS84_B = WGS84_A * (1.0 - WGS84_F)  # m, semi-minor axis (6356752.314245...)
WGS84_E2 = WGS84_F * (2.0 - WGS84_F)  # first eccentricity squared
EARTH_ROTATION_RATE = 7.292115e-5    # rad/s, WGS-84 nominal
EARTH_MEAN_RADIUS = 6371008.8        # m, IUGG mean radius R1 = (2a + b)/3, for great-circle distances

SECONDS_PER_DAY = 86400.0
DEG = np.pi / 180.0                  # radians per degree
ARCSEC = DEG / 3600.0                # radians per arcsecond


def deg2rad(x):
    return np.asarray(x, dtype=float) * DEG


def rad2deg(x):
    return np.asarray(x, dtype=float) / DEG


def arcsec2rad(x):
    return np.asarray(x, dtype=float) * ARCSEC


def rad2arcsec(x):
    return np.asarray(x, dtype=float) / ARCSEC
