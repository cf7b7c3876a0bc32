"""Fast single 3-vector operations for the simulator's inner loop.

np.cross on (3,) arrays costs ~50 us (axis bookkeeping); these do the same arithmetic in ~1 us.
Batched code keeps using numpy; tests check these against np.cross and host.core.rotations.
"""
from __future__ import annotations

import numpy as np


def cross3(a, b) -> np.ndarray:
    a0, a1, a2 = a
    b0, b1, b2 = b
    return np.array([a1 * b2 - a2 * b1, a2 * b0 - a0 * b2, a0 * b1 - a1 * b0])


def quat_rate3(q, w) -> np.ndarray:
    """Paper 001 eq. (3) for one quaternion (scalar last): q̇ = ½ [q4·ω − ω×q_v ; −ω·q_v].

    The same as host.core.rotations.quat_rate (0.5·Ω(ω)·q), written out; tests/host/plant/test_dynamics.py
    checks the two agree.
    """
    q1, q2, q3, q4 = q
    wx, wy, wz = w
    return 0.5 * np.array([q4 * wx - (wy * q3 - wz * q2),
                           q4 * wy - (wz * q1 - wx * q3),
                           q4 * wz - (wx * q2 - wy * q1),
                           -(wx * q1 + wy * q2 + wz * q3)])


def dcm_from_quat3(q) -> np.ndarray:
    """host.core.rotations.dcm_from_quat (Wie's C(q), reference -> body) for one quaternion, written out."""
    q1, q2, q3, q4 = q
    return np.array([
        [1 - 2 * (q2 * q2 + q3 * q3), 2 * (q1 * q2 + q3 * q4), 2 * (q1 * q3 - q2 * q4)],
        [2 * (q2 * q1 - q3 * q4), 1 - 2 * (q1 * q1 + q3 * q3), 2 * (q2 * q3 + q1 * q4)],
        [2 * (q3 * q1 + q2 * q4), 2 * (q3 * q2 - q1 * q4), 1 - 2 * (q1 * q1 + q2 * q2)],
    ])
