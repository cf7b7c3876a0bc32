"""Staring guidance: desired frame S_d, desired angular velocity and its derivative, analytic.

Computed from instantaneous inputs only, as the on-board controller must (UTC, GPS R_s/V_s in ECI,
target geodetic lon/lat): the target's ECI position/velocity/acceleration from GMST, the
line of sight u = r_T - R_s, and the orbit normal n = R_s x V_s / |R_s x V_s|.

    z_d = u/|u|                    (boresight on the target)
    x_d = unit(y_o x z_d),  y_o = -n   (= unit(z_d x n); the second axis from the orbit normal,
                                        Lian, Gao & Zeng, JGCD 40(5) 2017)
    y_d = z_d x x_d

so S_d = S_o when the target is at nadir. L_di has rows x_d, y_d, z_d (ECI components).
That is the ``second_axis="orbit_normal"`` rule. The DEFAULT is ``"along_track"``
(y_d = unit(z_d x x_o), x_d = y_d x z_d): it is also built from the orbit normal (x_o = y_o x z_o)
and it is the only one of the two that keeps all 100 staring targets inside the paper's own
Table 2 envelope (|omega_dz| <= 0.042 deg/s vs 0.156 deg/s; docs/guidance.md, "Choice").

Rates (derivation in docs/guidance.md): for an orthonormal triad e_k with de_k/dt = w x e_k,
    w_x = y' . z,   w_y = z' . x,   w_z = x' . y        (components in S_d)
and the derivative of those components (= the inertial derivative expressed in S_d, since
w x w = 0) is
    w_x' = y'' . z + y' . z',   w_y' = z'' . x + z' . x',   w_z' = x'' . y + x' . y'.
The unit-vector derivatives come from u' = v_T - V_s, u'' = a_T + mu R_s/|R_s|^3 (two-body), and
n' = 0 (two-body: d(R x V)/dt = R x a = 0). Nothing here is numerically differentiated.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from host.core.constants import MU_EARTH
from host.plant.earth import target_eci


@dataclass(frozen=True)
class DesiredState:
    L_di: np.ndarray        # (3,3) passive DCM inertial -> desired frame
    omega_d: np.ndarray     # (3,) desired angular velocity of S_d w.r.t. S_i, in S_d, rad/s
    omegadot_d: np.ndarray  # (3,) its time derivative, in S_d, rad/s^2


def _dot(a, b):
    return np.sum(a * b, -1, keepdims=True)


def _unit_with_derivatives(w, w1, w2):
    """e = w/|w| and its first two time derivatives from those of w (all (...,3)).

    With s = |w|, e = w/s:  s' = e.w',  e' = (w' - e s')/s,  s'' = e'.w' + e.w'',
    e'' = (w'' - 2 e' s' - e s'')/s   (from w = s e differentiated twice).
    """
    s = np.linalg.norm(w, axis=-1, keepdims=True)
    e = w / s
    s1 = _dot(e, w1)
    e1 = (w1 - e * s1) / s
    s2 = _dot(e1, w1) + _dot(e, w2)
    e2 = (w2 - 2.0 * e1 * s1 - e * s2) / s
    return e, e1, e2


def two_body_acceleration(R_s) -> np.ndarray:
    R_s = np.asarray(R_s, dtype=float)
    r = np.linalg.norm(R_s, axis=-1, keepdims=True)
    return -MU_EARTH * R_s / r**3


SECOND_AXIS_RULES = ("orbit_normal", "along_track")
# The paper flies the NN for all 100 targets; only this rule keeps them inside Table 2.
DEFAULT_SECOND_AXIS = "along_track"


def desired_axes(jd_days, sec_of_day, R_s, V_s, lon, lat, height=0.0, second_axis: str = DEFAULT_SECOND_AXIS):
    """The S_d axes in ECI and their first and second time derivatives.

    Returns ((x, x', x''), (y, y', y''), (z, z', z'')), each vector (...,3). Batch-friendly: the
    time tag, R_s, V_s and the target may carry matching leading dimensions.

    second_axis: "orbit_normal" (x_d = unit(y_o x z_d), x_d perpendicular to the orbit normal) or
    "along_track" (y_d = unit(z_d x x_o), y_d perpendicular to the orbital x_o). Both give S_o
    when the target is at nadir; they differ by a rotation about z_d that grows with the
    cross-track look angle (docs/guidance.md compares their rates with Table 2).
    """
    if second_axis not in SECOND_AXIS_RULES:
        raise ValueError(f"second_axis must be one of {SECOND_AXIS_RULES}, not {second_axis!r}")
    R_s, V_s = np.asarray(R_s, dtype=float), np.asarray(V_s, dtype=float)
    a_s = two_body_acceleration(R_s)
    r_t, v_t, a_t = target_eci(jd_days, sec_of_day, lon, lat, height)
    z, z1, z2 = _unit_with_derivatives(r_t - R_s, v_t - V_s, a_t - a_s)

    h = np.cross(R_s, V_s)
    n = h / np.linalg.norm(h, axis=-1, keepdims=True)  # constant under two-body motion: n' = 0

    if second_axis == "orbit_normal":
        # x_d direction: y_o x z_d = -n x z_d = z_d x n
        x, x1, x2 = _unit_with_derivatives(np.cross(z, n), np.cross(z1, n), np.cross(z2, n))
        y = np.cross(z, x)
        y1 = np.cross(z1, x) + np.cross(z, x1)
        y2 = np.cross(z2, x) + 2.0 * np.cross(z1, x1) + np.cross(z, x2)
    else:
        # x_o = y_o x z_o = n x R_hat, differentiated through R_hat (n constant)
        rh, rh1, rh2 = _unit_with_derivatives(R_s, V_s, a_s)
        xo, xo1, xo2 = np.cross(n, rh), np.cross(n, rh1), np.cross(n, rh2)
        y, y1, y2 = _unit_with_derivatives(
            np.cross(z, xo), np.cross(z1, xo) + np.cross(z, xo1),
            np.cross(z2, xo) + 2.0 * np.cross(z1, xo1) + np.cross(z, xo2))
        x = np.cross(y, z)
        x1 = np.cross(y1, z) + np.cross(y, z1)
        x2 = np.cross(y2, z) + 2.0 * np.cross(y1, z1) + np.cross(y, z2)
    return (x, x1, x2), (y, y1, y2), (z, z1, z2)


def desired_state(jd_days, sec_of_day, R_s, V_s, lon: float, lat: float,
                  height: float = 0.0, second_axis: str = DEFAULT_SECOND_AXIS) -> DesiredState:
    """Desired attitude L_di, omega_d and omegadot_d (in S_d) for staring at (lon, lat, height).

    jd_days, sec_of_day: UTC time tag (host.core.timebase); R_s [m], V_s [m/s] in ECI; lon, lat [rad]
    geodetic on WGS-84; height [m] above the ellipsoid. Works on batches (leading dimensions).
    second_axis: see desired_axes. Singular only when the line of sight is parallel to the orbit
    normal ("orbit_normal") or to x_o ("along_track"): a target 90 deg from nadir, never visible.
    """
    (x, x1, x2), (y, y1, y2), (z, z1, z2) = desired_axes(jd_days, sec_of_day, R_s, V_s, lon, lat,
                                                         height, second_axis)
    L_di = np.stack([x, y, z], -2)
    omega = np.concatenate([_dot(y1, z), _dot(z1, x), _dot(x1, y)], -1)
    omegadot = np.concatenate([_dot(y2, z) + _dot(y1, z1),
                               _dot(z2, x) + _dot(z1, x1),
                               _dot(x2, y) + _dot(x1, y1)], -1)
    return DesiredState(L_di=L_di, omega_d=omega, omegadot_d=omegadot)
