"""Two-body orbit (paper 001 eq. 1-2): Keplerian elements -> ECI, RK4 propagation, an analytic
Kepler propagator for checks, and the Table 5 orbit at 2017-05-31 04:40:00 UTC.

State vectors are [R_s, V_s] = (...,6) in metres and m/s, ECI (host.plant.earth). Angles in radians.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from host.core.constants import DEG, MU_EARTH
from host.core.rotations import frame_rot_x, frame_rot_z
from host.core.timebase import utc_to_jd


@dataclass(frozen=True)
class KeplerianElements:
    a: float      # m, semi-major axis (negative for a hyperbola)
    e: float      # eccentricity
    inc: float    # rad, inclination
    raan: float   # rad, right ascension of the ascending node
    argp: float   # rad, argument of perigee
    nu: float     # rad, true anomaly


def L_ip(inc, raan, argp) -> np.ndarray:
    """Passive DCM perifocal -> ECI: L_pi = R3(argp) R1(inc) R3(raan) (frame rotations)."""
    return np.swapaxes(frame_rot_z(argp) @ frame_rot_x(inc) @ frame_rot_z(raan), -1, -2)


def conic_to_eci(p, e, inc, raan, argp, nu, mu: float = MU_EARTH):
    """Semi-latus rectum p and angles -> (R, V) in ECI; valid for every conic (incl. e >= 1)."""
    p, e, nu = (np.asarray(v, dtype=float) for v in (p, e, nu))
    r = p / (1.0 + e * np.cos(nu))
    zero = np.zeros_like(r * nu)
    r_pf = np.stack([r * np.cos(nu), r * np.sin(nu), zero], -1)
    k = np.sqrt(mu / p)
    v_pf = np.stack([-k * np.sin(nu), k * (e + np.cos(nu)), zero], -1)
    L = L_ip(inc, raan, argp)
    return (L @ r_pf[..., None])[..., 0], (L @ v_pf[..., None])[..., 0]


def keplerian_to_eci(el: KeplerianElements, mu: float = MU_EARTH):
    """Elements -> (R [m], V [m/s]) in ECI."""
    return conic_to_eci(el.a * (1.0 - el.e**2), el.e, el.inc, el.raan, el.argp, el.nu, mu)


def state_from_elements(el: KeplerianElements, mu: float = MU_EARTH) -> np.ndarray:
    R, V = keplerian_to_eci(el, mu)
    return np.concatenate([R, V], -1)


# ----------------------------------------------------------------------------- propagation


def two_body_rhs(state) -> np.ndarray:
    """Eq. 1-2: d/dt [R, V] = [V, -mu R/|R|^3]."""
    state = np.asarray(state, dtype=float)
    R, V = state[..., :3], state[..., 3:]
    r = np.linalg.norm(R, axis=-1, keepdims=True)
    return np.concatenate([V, -MU_EARTH * R / r**3], -1)


def rk4_step(state, dt: float) -> np.ndarray:
    k1 = two_body_rhs(state)
    k2 = two_body_rhs(state + 0.5 * dt * k1)
    k3 = two_body_rhs(state + 0.5 * dt * k2)
    k4 = two_body_rhs(state + dt * k3)
    return state + (dt / 6.0) * (k1 + 2.0 * k2 + 2.0 * k3 + k4)


def propagate_rk4(state0, dt: float, n_steps: int) -> np.ndarray:
    """States at t = 0, dt, ..., n_steps*dt: array (n_steps+1, ..., 6)."""
    out = np.empty((n_steps + 1,) + np.shape(state0))
    out[0] = state0
    for k in range(n_steps):
        out[k + 1] = rk4_step(out[k], dt)
    return out


def specific_energy(state) -> np.ndarray:
    state = np.asarray(state, dtype=float)
    return 0.5 * np.sum(state[..., 3:] ** 2, -1) - MU_EARTH / np.linalg.norm(state[..., :3], axis=-1)


def angular_momentum(state) -> np.ndarray:
    state = np.asarray(state, dtype=float)
    return np.cross(state[..., :3], state[..., 3:])


def mean_motion(a: float, mu: float = MU_EARTH) -> float:
    return float(np.sqrt(mu / a**3))


def true_anomaly_after(el: KeplerianElements, dt, mu: float = MU_EARTH):
    """Elliptic Kepler problem: the true anomaly dt seconds after the epoch of ``el``."""
    e = el.e
    E0 = 2.0 * np.arctan2(np.sqrt(1.0 - e) * np.sin(el.nu / 2.0), np.sqrt(1.0 + e) * np.cos(el.nu / 2.0))
    M = E0 - e * np.sin(E0) + mean_motion(el.a, mu) * np.asarray(dt, dtype=float)
    E = M.copy() if np.ndim(M) else np.array(M)
    for _ in range(50):  # Newton on Kepler's equation; quadratic, converged long before 50
        E = E - (E - e * np.sin(E) - M) / (1.0 - e * np.cos(E))
    return 2.0 * np.arctan2(np.sqrt(1.0 + e) * np.sin(E / 2.0), np.sqrt(1.0 - e) * np.cos(E / 2.0))


def kepler_state(el: KeplerianElements, dt, mu: float = MU_EARTH) -> np.ndarray:
    """Exact two-body state dt seconds after the epoch of an elliptic orbit: (..., 6)."""
    nu = true_anomaly_after(el, dt, mu)
    R, V = conic_to_eci(el.a * (1.0 - el.e**2), el.e, el.inc, el.raan, el.argp, nu, mu)
    return np.concatenate([R, V], -1)


# ----------------------------------------------------------------------------- Table 5 scenario

TABLE5_EPOCH_UTC = (2017, 5, 31, 4, 40, 0.0)
TABLE5_EPOCH = utc_to_jd(*TABLE5_EPOCH_UTC)  # (jd_days, sec_of_day) = (2457905, 16800.0)
TABLE5_ELEMENTS = KeplerianElements(
    a=6878.14e3, e=0.0, inc=97.3 * DEG, raan=255.0 * DEG, argp=0.0, nu=145.0 * DEG
)


def table5_initial_state() -> np.ndarray:
    """[R_s, V_s] (6,) of the Table 5 orbit at its epoch TABLE5_EPOCH."""
    return state_from_elements(TABLE5_ELEMENTS)
