"""WGS-84 Earth: geodetic <-> ECEF, ECEF -> ECI by GMST, and a ground target's ECI kinematics.

ECI here is the mean-of-date equator/equinox frame S_i that the GMST rotation maps to ECEF:
precession-nutation (equation of the equinoxes < 1.2 arcsec) and polar motion are not modelled,
and UT1 = UTC (host.core.timebase). The Earth rotates about z_i at the GMST rate, so a fixed ground
point has v = w x r and a = w x (w x r) in ECI with w = [0, 0, gmst_rate].
"""
from __future__ import annotations

import numpy as np

from host.core.constants import WGS84_A, WGS84_E2
from host.core.rotations import frame_rot_z
from host.core.timebase import gmst, gmst_rate


def geodetic_to_ecef(lon, lat, height=0.0) -> np.ndarray:
    """Geodetic longitude, latitude [rad] and ellipsoidal height [m] -> ECEF position [m] (...,3)."""
    lon, lat, height = np.broadcast_arrays(*(np.asarray(v, dtype=float) for v in (lon, lat, height)))
    sl, cl = np.sin(lat), np.cos(lat)
    n = WGS84_A / np.sqrt(1.0 - WGS84_E2 * sl * sl)  # prime-vertical radius of curvature
    return np.stack([(n + height) * cl * np.cos(lon), (n + height) * cl * np.sin(lon),
                     (n * (1.0 - WGS84_E2) + height) * sl], -1)


def ecef_to_geodetic(r_ecef, iterations: int = 6):
    """ECEF [m] -> (lon, lat [rad], height [m]); fixed-point iteration on latitude (mm-exact
    after 4 iterations for points near the surface; not meant for the Earth's centre)."""
    r = np.asarray(r_ecef, dtype=float)
    x, y, z = r[..., 0], r[..., 1], r[..., 2]
    p = np.hypot(x, y)
    lat = np.arctan2(z, p * (1.0 - WGS84_E2))
    for _ in range(iterations):
        n = WGS84_A / np.sqrt(1.0 - WGS84_E2 * np.sin(lat) ** 2)
        lat = np.arctan2(z + WGS84_E2 * n * np.sin(lat), p)
    n = WGS84_A / np.sqrt(1.0 - WGS84_E2 * np.sin(lat) ** 2)
    # height along the normal, well conditioned at all latitudes
    height = p * np.cos(lat) + z * np.sin(lat) - n * (1.0 - WGS84_E2 * np.sin(lat) ** 2)
    return np.arctan2(y, x), lat, height


def local_up(lon, lat) -> np.ndarray:
    """Unit ellipsoid normal (geodetic up) in ECEF."""
    lon, lat = np.broadcast_arrays(np.asarray(lon, dtype=float), np.asarray(lat, dtype=float))
    return np.stack([np.cos(lat) * np.cos(lon), np.cos(lat) * np.sin(lon), np.sin(lat)], -1)


def L_ei(jd_days, sec_of_day) -> np.ndarray:
    """Passive DCM ECI -> ECEF: the frame rotated by GMST about z (v_e = L_ei v_i)."""
    return frame_rot_z(gmst(jd_days, sec_of_day))


def ecef_to_eci(r_ecef, jd_days, sec_of_day) -> np.ndarray:
    r = np.asarray(r_ecef, dtype=float)
    return np.einsum("...ji,...j->...i", L_ei(jd_days, sec_of_day), r)  # L_ie = L_ei^T


def eci_to_ecef(r_eci, jd_days, sec_of_day) -> np.ndarray:
    r = np.asarray(r_eci, dtype=float)
    return np.einsum("...ij,...j->...i", L_ei(jd_days, sec_of_day), r)


def earth_rate_vector(jd_days, sec_of_day) -> np.ndarray:
    """Earth angular velocity in ECI [rad/s], (...,3)."""
    w = np.asarray(gmst_rate(jd_days, sec_of_day), dtype=float)
    zero = np.zeros_like(w)
    return np.stack([zero, zero, w], -1)


def target_eci(jd_days, sec_of_day, lon, lat, height=0.0):
    """Position [m], velocity [m/s] and acceleration [m/s^2] in ECI of a point fixed on the Earth."""
    r = ecef_to_eci(geodetic_to_ecef(lon, lat, height), jd_days, sec_of_day)
    w = earth_rate_vector(jd_days, sec_of_day)
    w = np.broadcast_to(w, r.shape)
    v = np.cross(w, r)
    return r, v, np.cross(w, v)


def elevation(r_sat_eci, jd_days, sec_of_day, lon, lat, height=0.0):
    """Elevation [rad] of the satellite above the target's local geodetic horizon."""
    r_t = target_eci(jd_days, sec_of_day, lon, lat, height)[0]
    up = ecef_to_eci(local_up(lon, lat), jd_days, sec_of_day)
    los = np.asarray(r_sat_eci, dtype=float) - r_t
    s = np.sum(los * up, -1) / np.linalg.norm(los, axis=-1)
    return np.arcsin(np.clip(s, -1.0, 1.0))
