"""The sensor and actuator errors of paper 001 Table 6, resolved to SI values per axis.

Table 6 states each error as a constant part and a random part ("3σ" for the star sensor, "1σ" for
the gyro and the wheels, the wheel error in "nm"). How those words are read — which σ a value is,
whether it applies to each axis or to the magnitude of the 3-axis error, how often a random error is
drawn — is a *reading*, written in a scenario file (host.sim.scenario_file) and resolved here to
what the simulators use:

    measured = true + bias + noise,   noise ~ N(0, sigma²) per axis, independent across axes,

with a new draw every `period` seconds of simulated time, held in between (draw i covers
[i·period, (i+1)·period)). The star sensor and the gyro are read at the control instants, so a
period at or below the control period gives an independent draw at every control step. The wheel
error is added to each wheel's torque at every plant step, so a period of one plant step makes it
white at the integration rate and a period of one control period holds it with the command.

Both simulators (host.sim.simulator, host.sim.batched) draw their noise through `draw_noise`, so a
scenario's noise is the same whatever simulator flies it. With the `table6` reading (periods of one
control period) the draws are exactly those of the earlier per-step `rng.normal(0, σ, 3)` calls.
"""
from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from host.core.constants import ARCSEC, DEG
from host.errors import HostError

DEG_PER_HOUR = DEG / 3600.0   # rad/s
DRAW_TOLERANCE = 1e-9         # s: a sample on a draw boundary belongs to the later draw


@dataclass(frozen=True)
class ErrorSource:
    """One error source: constant bias and 1σ random error per axis (SI), the random draw's period."""
    bias: tuple[float, float, float]
    sigma: tuple[float, float, float]
    period: float                         # s between independent random draws

    def __post_init__(self):
        for name in ("bias", "sigma"):
            v = np.asarray(getattr(self, name), float)
            if v.shape != (3,) or not np.all(np.isfinite(v)):
                raise HostError(f"error source: {name} must be three finite numbers, got {getattr(self, name)!r}")
        if np.any(np.asarray(self.sigma, float) < 0):
            raise HostError(f"error source: sigma must be >= 0, got {self.sigma!r}")
        if not (np.isfinite(self.period) and self.period > 0):
            raise HostError(f"error source: period must be a positive number of seconds, got {self.period!r}")

    @property
    def bias_array(self) -> np.ndarray:
        return np.asarray(self.bias, float)

    @property
    def sigma_array(self) -> np.ndarray:
        return np.asarray(self.sigma, float)

    def scaled(self, factor: float) -> "ErrorSource":
        """The random part times `factor` (the constant part unchanged)."""
        return replace(self, sigma=tuple(float(s) * factor for s in self.sigma))

    def draw_index(self, times: np.ndarray) -> np.ndarray:
        """Which draw holds at each sample time: floor(t / period) (a boundary sample takes the later)."""
        return np.floor(np.asarray(times, float) / self.period + DRAW_TOLERANCE).astype(np.int64)

    def draws(self, rng: np.random.Generator, times: np.ndarray) -> np.ndarray:
        """(len(times), 3) noise at the sample times: draw i = floor(t / period), one
        rng.normal(0, σ, (n, 3)) call for the draws the times need."""
        index = self.draw_index(times)
        n = int(index[-1]) + 1 if index.size else 0
        values = rng.normal(0.0, self.sigma_array, (n, 3))
        return values[index]


@dataclass(frozen=True)
class ErrorModel:
    """Star sensor (rad on each 3-1-2 angle of A_bo), gyro (rad/s on ω_b), wheels (N·m per wheel)."""
    reading: str
    star: ErrorSource
    gyro: ErrorSource
    wheels: ErrorSource

    def scaled(self, factor: float) -> "ErrorModel":
        """Every random error times `factor` (the ratio-vs-noise sweep); constants unchanged."""
        if not (np.isfinite(factor) and factor >= 0):
            raise HostError(f"noise scale must be a finite number >= 0, got {factor!r}")
        return replace(self, reading=f"{self.reading} x{factor:g} random", star=self.star.scaled(factor),
                       gyro=self.gyro.scaled(factor), wheels=self.wheels.scaled(factor))


@dataclass(frozen=True)
class NoiseTrack:
    """The random errors of one run: star and gyro at the control instants (n_ctrl, 3), the wheels
    at the plant steps (n_ctrl·substeps, 3). Zeros for a source that is switched off."""
    star: np.ndarray
    gyro: np.ndarray
    wheels: np.ndarray


def noise_generators(seed: int, stream: int) -> tuple[np.random.Generator, ...]:
    """Star-sensor, gyro and wheel generators of noise stream `stream` under `seed`."""
    return tuple(np.random.default_rng(s) for s in np.random.SeedSequence([seed, stream]).spawn(3))


def plant_times(n_ctrl: int, control_period: float, substeps: int) -> np.ndarray:
    """The plant-step instants of a run of n_ctrl control periods (where the wheel error is drawn)."""
    return np.arange(n_ctrl * substeps) * (control_period / substeps)


def draw_noise(model: ErrorModel, seed: int, stream: int, n_ctrl: int, control_period: float, substeps: int,
               sensors: bool = True, wheels: bool = True) -> NoiseTrack:
    """The noise of (seed, stream) for a run of n_ctrl control periods of `substeps` plant steps."""
    g_star, g_gyro, g_wheel = noise_generators(seed, stream)
    t_ctrl = np.arange(n_ctrl) * control_period
    t_plant = plant_times(n_ctrl, control_period, substeps)
    zeros_ctrl, zeros_plant = np.zeros((n_ctrl, 3)), np.zeros((n_ctrl * substeps, 3))
    return NoiseTrack(star=model.star.draws(g_star, t_ctrl) if sensors else zeros_ctrl,
                      gyro=model.gyro.draws(g_gyro, t_ctrl) if sensors else zeros_ctrl,
                      wheels=model.wheels.draws(g_wheel, t_plant) if wheels else zeros_plant)


# Today's reading of Table 6 (docs/simulation.md): per axis, the star sensor's 3″ as 3σ, the gyro's
# and the wheels' values as 1σ, "nm" as N·m, a new draw every control period.
TABLE6_ERRORS = ErrorModel(
    reading="table6",
    star=ErrorSource(bias=(3.0 * ARCSEC,) * 3, sigma=(1.0 * ARCSEC,) * 3, period=0.1),
    gyro=ErrorSource(bias=(0.15 * DEG_PER_HOUR,) * 3, sigma=(0.15 * DEG_PER_HOUR,) * 3, period=0.1),
    wheels=ErrorSource(bias=(0.01,) * 3, sigma=(0.01,) * 3, period=0.1),
)
