"""External disturbance torques M_ext (paper 001 eq. 4, Table 6), body axes, N·m.

One function per physical effect; the environment (Sun, density, field) comes from
host.plant.environment and is attitude-independent, so the simulator evaluates it once per time sample.
Stated spacecraft surface model (the paper cites a textbook, ref. [23], without numbers):

* gravity gradient: 3μ/r³ · r̂_b × (I r̂_b), exact for a rigid body in a central field;
* aerodynamic: flat projected area 4 m², C_d = 2.2, centre of pressure offset [0.10, 0.05, 0.20] m
  from the centre of mass; force −½ρC_dA|v|v with v relative to the co-rotating air;
* solar radiation: projected area 6 m² (body + panels), reflectivity 0.6 (force factor 1 + ρ),
  centre of pressure offset [0.05, 0.30, 0.10] m; force along −ŝ, zero in the Earth's shadow;
* magnetic: residual dipole [1, 1, 1] A·m² × tilted-dipole field.

At 500 km these give ~1e-5…1e-4 N·m each (gravity gradient up to ~1e-3 N·m at large off-nadir
angles), two orders below the 0.01 N·m wheel bias.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from host.core.constants import MU_EARTH
from host.plant.environment import SOLAR_PRESSURE
from host.core.vec3 import cross3


@dataclass(frozen=True)
class DisturbanceParams:
    drag_area: float = 4.0                       # m^2
    drag_coefficient: float = 2.2
    drag_cp_offset: np.ndarray = field(default_factory=lambda: np.array([0.10, 0.05, 0.20]))  # m, body
    srp_area: float = 6.0                        # m^2
    srp_reflectivity: float = 0.6
    srp_cp_offset: np.ndarray = field(default_factory=lambda: np.array([0.05, 0.30, 0.10]))   # m, body
    residual_dipole: np.ndarray = field(default_factory=lambda: np.array([1.0, 1.0, 1.0]))    # A m^2, body
    gravity_gradient: bool = True                # False: no gravity-gradient torque (a cross-check switch)


DEFAULT_DISTURBANCES = DisturbanceParams()


def gravity_gradient_torque(R_s, L_bi, inertia) -> np.ndarray:
    """3μ/r³ · r̂_b × (I r̂_b), r̂_b the unit position vector in body axes."""
    R_s = np.asarray(R_s, float)
    r = np.sqrt(R_s @ R_s)
    r_hat_b = L_bi @ (R_s / r)
    return 3.0 * MU_EARTH / r**3 * cross3(r_hat_b, inertia @ r_hat_b)


def aerodynamic_torque(rho: float, v_rel_eci, L_bi, p: DisturbanceParams) -> np.ndarray:
    """r_cp × F_drag with F_drag = −½ ρ C_d A |v| v (flat projected area, body axes)."""
    v_b = L_bi @ np.asarray(v_rel_eci, float)
    force = -0.5 * rho * p.drag_coefficient * p.drag_area * np.sqrt(v_b @ v_b) * v_b
    return cross3(p.drag_cp_offset, force)


def solar_radiation_torque(sun_dir_eci, sunlit: float, L_bi, p: DisturbanceParams) -> np.ndarray:
    """r_cp × F_srp with F_srp = −P A (1 + reflectivity) ŝ (ŝ: unit vector to the Sun)."""
    s_b = L_bi @ np.asarray(sun_dir_eci, float)
    force = -sunlit * SOLAR_PRESSURE * p.srp_area * (1.0 + p.srp_reflectivity) * s_b
    return cross3(p.srp_cp_offset, force)


def magnetic_torque(B_eci, L_bi, p: DisturbanceParams) -> np.ndarray:
    """m_residual × B (B in tesla, torque in N·m)."""
    return cross3(p.residual_dipole, L_bi @ np.asarray(B_eci, float))


def total_disturbance_torque(env, k: int, L_bi, inertia, p: DisturbanceParams) -> np.ndarray:
    """Sum of the four torques at sample k of a host.plant.environment.EnvironmentTrack."""
    gg = gravity_gradient_torque(env.R[k], L_bi, inertia) if p.gravity_gradient else np.zeros(3)
    return (gg
            + aerodynamic_torque(env.rho[k], env.v_rel[k], L_bi, p)
            + solar_radiation_torque(env.sun_dir[k], env.sunlit[k], L_bi, p)
            + magnetic_torque(env.B[k], L_bi, p))
