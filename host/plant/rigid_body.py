"""A rigid body without wheels on SO(3): J ω̇ = −ω × Jω + u + d(t), Ṙ = R[ω]×, and its RK4 step.

The plant of paper 000's example (section 4.2) and of the tanh law's closed-loop gate sequences;
written out on plain floats because a 3×3 numpy call costs more than the arithmetic (the example
takes ~10^5 RK4 steps). State y = [R (9, rows: body -> reference), ω (3, rad/s, body axes)].
The staring spacecraft with its wheels is host.plant.spacecraft (quaternion state).
"""
from __future__ import annotations

import math
from typing import Callable, Sequence

import numpy as np

Vec = tuple[float, float, float]


def paper000_disturbance(amplitude: float) -> Callable[[float], Vec]:
    """d(t) = a·[sin 0.1t, cos 0.2t, sin 0.2t] N·m (paper 000, section 4.2)."""
    def d(t: float) -> Vec:
        return (amplitude * math.sin(0.1 * t), amplitude * math.cos(0.2 * t), amplitude * math.sin(0.2 * t))
    return d


class RigidBody:
    """Rates and RK4 steps of [R, ω] for inertia J under a held torque u and a disturbance d(t)."""

    def __init__(self, inertia, disturbance: Callable[[float], Vec] | None = None):
        J = np.asarray(inertia, dtype=float)
        self.J = tuple(tuple(float(x) for x in row) for row in J)
        self.J_inv = tuple(tuple(float(x) for x in row) for row in np.linalg.inv(J))
        self.disturbance = disturbance or (lambda t: (0.0, 0.0, 0.0))

    def rates(self, t: float, y: Sequence[float], u: Vec) -> list[float]:
        """d/dt of [R rows, ω]; row i of Ṙ = R[ω]× is r_i × ω."""
        w0, w1, w2 = y[9], y[10], y[11]
        (a, b, c), (d, e, f), (g, h, i) = self.J
        h0, h1, h2 = a * w0 + b * w1 + c * w2, d * w0 + e * w1 + f * w2, g * w0 + h * w1 + i * w2
        dist = self.disturbance(t)
        m0 = -(w1 * h2 - w2 * h1) + u[0] + dist[0]
        m1 = -(w2 * h0 - w0 * h2) + u[1] + dist[1]
        m2 = -(w0 * h1 - w1 * h0) + u[2] + dist[2]
        (a, b, c), (d, e, f), (g, h, i) = self.J_inv
        out = []
        for k in (0, 3, 6):
            r0, r1, r2 = y[k], y[k + 1], y[k + 2]
            out += (r1 * w2 - r2 * w1, r2 * w0 - r0 * w2, r0 * w1 - r1 * w0)
        out += (a * m0 + b * m1 + c * m2, d * m0 + e * m1 + f * m2, g * m0 + h * m1 + i * m2)
        return out

    def rk4_step(self, t: float, y: Sequence[float], h: float, u: Vec) -> list[float]:
        """One RK4 step of length h with u held."""
        k1 = self.rates(t, y, u)
        k2 = self.rates(t + 0.5 * h, [a + 0.5 * h * b for a, b in zip(y, k1)], u)
        k3 = self.rates(t + 0.5 * h, [a + 0.5 * h * b for a, b in zip(y, k2)], u)
        k4 = self.rates(t + h, [a + h * b for a, b in zip(y, k3)], u)
        return [a + h / 6.0 * (b + 2.0 * (p + q) + r) for a, b, p, q, r in zip(y, k1, k2, k3, k4)]


def state(R, w) -> list[float]:
    """[R rows, ω] as a flat list of floats."""
    return [float(x) for x in np.asarray(R, dtype=float).reshape(9)] + [float(x) for x in w]


def rows(y: Sequence[float]):
    """R of a state as a tuple of rows."""
    return ((y[0], y[1], y[2]), (y[3], y[4], y[5]), (y[6], y[7], y[8]))
