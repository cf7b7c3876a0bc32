"""Sensor models (paper 001 Table 6): measured = true + bias + noise.

* Star sensor: measures A_bo (3-1-2 Euler angles of body w.r.t. the orbital frame).
* Gyro: measures ω_b.
* GPS: ideal (R_s, V_s returned exactly). The guidance is insensitive to metre-level GPS noise:
  10 m across a 500+ km line of sight is ~4″, which would only add a slowly varying pointing
  offset; the paper does not list a GPS error, so none is modelled.

The constant errors and the random errors' σ and draw period come from the scenario's error model
(host.plant.error_model: the `table6` reading is +3″ on each angle with σ = 1″, +0.15°/h with
σ = 0.15°/h); the noise itself is drawn once per run (error_model.draw_noise), so the seed only
changes the noise. "Errors off" gives perfect sensors (for tests).
"""
from __future__ import annotations

import numpy as np

from host.plant.error_model import ErrorSource


def measure(true_value, source: ErrorSource, noise, enabled: bool = True) -> np.ndarray:
    """A sensor reading: (true + bias) + noise, or the true value when the errors are off."""
    v = np.asarray(true_value, float)
    if not enabled:
        return v.copy()
    return (v + source.bias_array) + noise


class Gps:
    """Ideal GPS: position and velocity in ECI exactly as propagated."""

    def measure(self, R_s, V_s):
        return np.array(R_s, float), np.array(V_s, float)
