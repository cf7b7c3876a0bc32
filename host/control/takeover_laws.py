"""Paper 004's host laws (docs/gp-takeover.md section 5), float64: the baseline quaternion PD with the
prior model's gyroscopic term, and the GP law that subtracts the GP mean of the unknown term d and
stiffens its gains with the GP variance.

    baseline:  u_b  = sat( −k1 q_v − k2 ω + ω×(J_s ω + h_w) )
    GP law:    u_gp = sat( −K1(s) q_v − K2(s) ω + ω×(J_s ω + h_w) − μ(x) ),  x = [q_v, ω, ω̇ = 0]
               K_i(s) = k_i + (k̄_i − k_i) s,  s = max_k clamp(σ²_k / σ²_prior,k, 0, 1)

Regulation to q_d = [0, 0, 0, 1], ω_d = 0: the attitude error is the measured quaternion itself (sign
chosen with q4 ≥ 0, the shorter way round, as the GP's training data). The GP is any object with
`predict(x (9,)) -> (mean (3,), variance (3,))` in N·m and (N·m)²; its prior variance per axis (the
variance far from the data) normalises the schedule.

From the law's parameter file (codegen.units.gp.params.GpLawParams: the trained artifact, the gain
bounds, torque limit and J_s): `gp_law(params)` flies the artifact through `ArtifactPredictor`
(float64, codegen.units.gp.artifact.reference_predict on the artifact's arrays; prior variance per
axis s_y,k² σ_f²), `baseline_law(params)` the same gains' lower bounds without the GP.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import NamedTuple, Protocol

import numpy as np

from codegen.units.gp.artifact import GpArrays, reference_predict
from codegen.units.gp.params import GpLawParams
from host.core.vec3 import cross3
from host.errors import HostError
from host.plant.spacecraft import TABLE6_INERTIA

K1, K1_BAR = 4.0, 16.0       # N·m
K2, K2_BAR = 72.0, 144.0     # N·m·s/rad
TORQUE_MAX = 1.0             # N·m per axis


class Predictor(Protocol):
    def predict(self, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]: ...


class LawOutput(NamedTuple):
    torque: np.ndarray     # N·m, commanded, clipped
    mu: np.ndarray         # N·m, GP mean of d (zero for the baseline)
    var: np.ndarray        # (N·m)², GP variance of d (zero for the baseline)
    gains: np.ndarray      # (K1, K2)


@dataclass(frozen=True)
class Gains:
    k1: float = K1
    k1_bar: float = K1_BAR
    k2: float = K2
    k2_bar: float = K2_BAR

    def __post_init__(self):
        if not (0 < self.k1 <= self.k1_bar and 0 < self.k2 <= self.k2_bar):
            raise HostError(f"need 0 < k1 <= k1_bar and 0 < k2 <= k2_bar, got {self}")

    def scheduled(self, s: float) -> np.ndarray:
        """(K1, K2) affine in s ∈ [0, 1]: the lower bounds at s = 0, the upper at s = 1."""
        return np.array([self.k1 + (self.k1_bar - self.k1) * s, self.k2 + (self.k2_bar - self.k2) * s])


def attitude_error(q) -> np.ndarray:
    """q_v of the unit quaternion with q4 ≥ 0 (regulation to the reference frame)."""
    q = np.asarray(q, dtype=float)
    q = q / np.sqrt(q @ q)
    return q[:3] if q[3] >= 0.0 else -q[:3]


def gp_input(q, omega) -> np.ndarray:
    """x = [q_v, ω, ω̇ = 0]: the GP is evaluated at the reference acceleration (section 2)."""
    return np.concatenate([attitude_error(q), np.asarray(omega, float), np.zeros(3)])


def variance_fraction(var, prior_var) -> float:
    """s = max_k σ²_k / σ²_prior,k, clamped to [0, 1] (NaN → 1: unknown means uncertain)."""
    ratio = np.asarray(var, float) / np.asarray(prior_var, float)
    ratio = np.where(np.isnan(ratio), 1.0, ratio)
    return float(np.max(np.clip(ratio, 0.0, 1.0)))


def pd_torque(q_v, omega, h_w, k1: float, k2: float, prior_inertia) -> np.ndarray:
    """−k1 q_v − k2 ω + ω×(J_s ω + h_w), before the GP mean and the clip."""
    omega = np.asarray(omega, float)
    return -k1 * q_v - k2 * omega + cross3(omega, prior_inertia @ omega + np.asarray(h_w, float))


@dataclass(frozen=True)
class BaselineLaw:
    gains: Gains = field(default_factory=Gains)
    prior_inertia: np.ndarray = field(default_factory=lambda: TABLE6_INERTIA.copy())
    torque_max: float = TORQUE_MAX

    def __call__(self, q, omega, h_w) -> LawOutput:
        g = self.gains
        u = pd_torque(attitude_error(q), omega, h_w, g.k1, g.k2, self.prior_inertia)
        return LawOutput(np.clip(u, -self.torque_max, self.torque_max), np.zeros(3), np.zeros(3),
                         np.array([g.k1, g.k2]))


@dataclass(frozen=True)
class GpLaw:
    predictor: Predictor
    prior_variance: np.ndarray          # (3,) (N·m)²: the GP's variance far from the data
    gains: Gains = field(default_factory=Gains)
    prior_inertia: np.ndarray = field(default_factory=lambda: TABLE6_INERTIA.copy())
    torque_max: float = TORQUE_MAX

    def __post_init__(self):
        pv = np.asarray(self.prior_variance, dtype=float)
        if pv.shape != (3,) or not np.all(np.isfinite(pv)) or np.any(pv <= 0):
            raise HostError(f"prior_variance must be 3 positive finite numbers, got {self.prior_variance!r}")
        if not callable(getattr(self.predictor, "predict", None)):
            raise HostError("predictor must have predict(x) -> (mean (3,), variance (3,))")

    def __call__(self, q, omega, h_w) -> LawOutput:
        mu, var = self.predictor.predict(gp_input(q, omega))
        mu, var = np.asarray(mu, float).reshape(3), np.asarray(var, float).reshape(3)
        if not np.all(np.isfinite(mu)):
            mu = np.zeros(3)            # compensate nothing rather than fly a NaN
        K = self.gains.scheduled(variance_fraction(var, self.prior_variance))
        u = pd_torque(attitude_error(q), omega, h_w, K[0], K[1], self.prior_inertia) - mu
        return LawOutput(np.clip(u, -self.torque_max, self.torque_max), mu, var, K)


# ----------------------------------------------------------------------------- from the law's file


@dataclass(frozen=True)
class ArtifactPredictor:
    """The trained GP of an artifact, float64 (reference_predict): latent mean and variance of d."""

    arrays: GpArrays

    def predict(self, x) -> tuple[np.ndarray, np.ndarray]:
        mean, var = reference_predict(self.arrays, np.asarray(x, dtype=float).reshape(1, -1))
        return mean[0], var[0]

    @property
    def prior_variance(self) -> np.ndarray:
        """s_y,k² σ_f² per axis, (N·m)²: the latent variance far from the data (without the jitter)."""
        return np.asarray(self.arrays.output_scale, float) ** 2 * float(self.arrays.outputscale)


def file_gains(params: GpLawParams) -> Gains:
    return Gains(params.k1, params.k1_bar, params.k2, params.k2_bar)


def gp_law(params: GpLawParams) -> GpLaw:
    """The GP law of the parameter file: its artifact, gain bounds, torque limit and J_s."""
    predictor = ArtifactPredictor(params.gp.arrays)
    return GpLaw(predictor, predictor.prior_variance, file_gains(params), np.array(params.inertia, dtype=float),
                 float(params.torque_max))


def baseline_law(params: GpLawParams) -> BaselineLaw:
    """The baseline PD of the parameter file: gains k1, k2 (the GP law's lower bounds), torque limit, J_s."""
    return BaselineLaw(file_gains(params), np.array(params.inertia, dtype=float), float(params.torque_max))
