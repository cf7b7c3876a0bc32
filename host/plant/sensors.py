"""Sensor models (paper 001 Table 6), seeded with numpy Generators.

* Star sensor: measures A_bo (3-1-2 Euler angles of body w.r.t. the orbital frame) with a
  constant error of +3″ on each angle and white noise of 3″ (3σ), i.e. σ = 1″, per sample.
* Gyro: measures ω_b with a constant bias of +0.15°/h on each axis and white noise 0.15°/h (1σ).
* GPS: ideal (R_s, V_s returned exactly). The guidance is insensitive to metre-level GPS noise:
  10 m across a 500+ km line of sight is ~4″, which would only add a slowly varying pointing
  offset; the paper does not list a GPS error, so none is modelled.

The constant errors have a fixed sign (+) so every seed sees the same systematic error and the
seed only changes the noise; "errors off" gives perfect sensors (for tests).
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from host.core.constants import ARCSEC, DEG

DEG_PER_HOUR = DEG / 3600.0   # rad/s


@dataclass(frozen=True)
class SensorErrors:
    star_bias: np.ndarray = field(default_factory=lambda: np.full(3, 3.0 * ARCSEC))   # rad
    star_sigma: float = 3.0 * ARCSEC / 3.0                                              # rad, 1σ
    gyro_bias: np.ndarray = field(default_factory=lambda: np.full(3, 0.15 * DEG_PER_HOUR))  # rad/s
    gyro_sigma: float = 0.15 * DEG_PER_HOUR                                             # rad/s, 1σ


TABLE6_SENSORS = SensorErrors()


class StarSensor:
    def __init__(self, errors: SensorErrors, rng: np.random.Generator, enabled: bool = True):
        self.errors, self.rng, self.enabled = errors, rng, enabled

    def measure(self, A_bo_true) -> np.ndarray:
        A = np.asarray(A_bo_true, float)
        if not self.enabled:
            return A.copy()
        return A + self.errors.star_bias + self.rng.normal(0.0, self.errors.star_sigma, 3)


class Gyro:
    def __init__(self, errors: SensorErrors, rng: np.random.Generator, enabled: bool = True):
        self.errors, self.rng, self.enabled = errors, rng, enabled

    def measure(self, omega_b_true) -> np.ndarray:
        w = np.asarray(omega_b_true, float)
        if not self.enabled:
            return w.copy()
        return w + self.errors.gyro_bias + self.rng.normal(0.0, self.errors.gyro_sigma, 3)


class Gps:
    """Ideal GPS: position and velocity in ECI exactly as propagated."""

    def measure(self, R_s, V_s):
        return np.array(R_s, float), np.array(V_s, float)
