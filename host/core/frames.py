"""Orbital reference frame S_o (paper 001 sec. 2.1): z_o to the Earth's centre, y_o along minus
the orbit normal (minus the orbital angular momentum), x_o = y_o x z_o (along the velocity for a
circular orbit)."""
from __future__ import annotations

import numpy as np


def _unit(v):
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


def orbital_axes(R_s, V_s):
    """Unit vectors x_o, y_o, z_o in ECI components, each (...,3)."""
    R_s, V_s = np.asarray(R_s, dtype=float), np.asarray(V_s, dtype=float)
    z_o = -_unit(R_s)
    y_o = -_unit(np.cross(R_s, V_s))
    return np.cross(y_o, z_o), y_o, z_o


def L_oi(R_s, V_s) -> np.ndarray:
    """Passive DCM S_i -> S_o (rows are the S_o axes in ECI components): v_o = L_oi v_i."""
    return np.stack(orbital_axes(R_s, V_s), -2)
