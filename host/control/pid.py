"""The paper's PID law (paper 001 Sec. 3, Table 1), per axis, errors in DEGREES, torque in N·m:

    M_cmd = −( Kp·A_bd° + Ki·∫A_bd° dt + Kd·ω_e°/s ),   then clipped to ±torque_limit.

The minus sign makes it stabilising: a positive A_bd (body rotated positively from S_d) needs a
negative torque. The "derivative" is ω_e itself (rate feedback from the gyro, as in the paper),
not a differentiated angle. The integrator uses the control period (rectangle rule) and stops
integrating on an axis while that axis is saturated (anti-windup). Table 1 has Ki = 0.
A non-finite input (a failed sensor) gives zero torque, never NaN.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from host.control.batch import BatchLayout, BatchMeasurement, BatchOutput
from host.core.constants import DEG
from host.control.controllers import ControlOutput, Measurement
from host.errors import HostError
from host.gnc.preprocess import preprocess


@dataclass(frozen=True)
class PidGains:
    kp: np.ndarray = field(default_factory=lambda: np.array([17.0, 54.0, 18.0]))  # N·m/°
    ki: np.ndarray = field(default_factory=lambda: np.array([0.0, 0.0, 0.0]))     # N·m/(°·s)
    kd: np.ndarray = field(default_factory=lambda: np.array([46.0, 77.0, 50.0]))  # N·m/(°/s)


TABLE1_GAINS = PidGains()


class PidLaw:
    """The PID law on (A_bd, ω_e) with its integrator state; reusable as a fallback law."""

    def __init__(self, gains: PidGains = TABLE1_GAINS, torque_limit: float = 1.0,
                 control_period: float = 0.1):
        self.gains = gains
        self.torque_limit = float(torque_limit)
        self.control_period = float(control_period)
        self.integral_deg_s = np.zeros(3)

    def reset(self) -> None:
        self.integral_deg_s = np.zeros(3)

    def torque(self, A_bd, omega_e) -> np.ndarray:
        """Saturated torque command [N·m] for errors in rad and rad/s; advances the integrator."""
        A_deg = np.asarray(A_bd, float) / DEG
        w_deg = np.asarray(omega_e, float) / DEG
        if not (np.all(np.isfinite(A_deg)) and np.all(np.isfinite(w_deg))):
            return np.zeros(3)   # never command NaN/Inf; the integrator keeps its last good value
        g = self.gains
        integral_next = self.integral_deg_s + A_deg * self.control_period
        raw = -(g.kp * A_deg + g.ki * integral_next + g.kd * w_deg)
        saturated = np.abs(raw) > self.torque_limit
        self.integral_deg_s = np.where(saturated, self.integral_deg_s, integral_next)
        return np.clip(raw, -self.torque_limit, self.torque_limit)


class PidController:
    """Controller-interface wrapper: preprocess the measurement, then apply the PID law."""

    name = "pid"

    def __init__(self, gains: PidGains = TABLE1_GAINS, torque_limit: float = 1.0,
                 control_period: float = 0.1):
        self.law = PidLaw(gains, torque_limit, control_period)

    def reset(self) -> None:
        self.law.reset()

    def step(self, m: Measurement) -> ControlOutput:
        x = preprocess(m)
        M = self.law.torque(x.A_bd, x.omega_e)
        return ControlOutput(torque=M, mode="pid", info={"A_bd": x.A_bd, "omega_e": x.omega_e})


def make_pid_controller(*, torque_limit: float, control_period: float,
                        gains: PidGains = TABLE1_GAINS) -> PidController:
    return PidController(gains, torque_limit, control_period)


# ----------------------------------------------------------------------------- batched (rows)

@dataclass(frozen=True)
class GainSets:
    """G PID gain sets (paper units: N·m/°, N·m/(°·s), N·m/(°/s)), each (G, 3) per axis."""
    kp: np.ndarray
    ki: np.ndarray
    kd: np.ndarray

    def __post_init__(self):
        shapes = {np.shape(self.kp), np.shape(self.ki), np.shape(self.kd)}
        if len(shapes) != 1 or len(next(iter(shapes))) != 2 or next(iter(shapes))[1] != 3:
            raise HostError(f"gain sets: kp, ki, kd must all be (G, 3) arrays, got {sorted(shapes)}")
        for name in ("kp", "ki", "kd"):
            if not np.all(np.isfinite(getattr(self, name))):
                raise HostError(f"gain sets: {name} has non-finite entries")

    def __len__(self) -> int:
        return int(np.shape(self.kp)[0])

    @classmethod
    def single(cls, kp, ki, kd) -> "GainSets":
        return cls(np.atleast_2d(np.asarray(kp, float)), np.atleast_2d(np.asarray(ki, float)),
                   np.atleast_2d(np.asarray(kd, float)))

    @classmethod
    def of(cls, gains: PidGains) -> "GainSets":
        return cls.single(gains.kp, gains.ki, gains.kd)


class PidBatch:
    """PidLaw on rows, one gain set per variant (the Table 7 grid flies G gain sets side by side)."""

    name = "pid"

    def __init__(self, gains: GainSets, torque_limit: float = 1.0, control_period: float = 0.1):
        self.gains, self.torque_limit, self.control_period = gains, float(torque_limit), float(control_period)
        self.variants = len(gains)

    def reset(self, layout: BatchLayout) -> None:
        self.kp, self.ki, self.kd = (layout.per_variant(np.asarray(a, float))
                                     for a in (self.gains.kp, self.gains.ki, self.gains.kd))
        self.integral = np.zeros((layout.rows, 3))

    def step(self, m: BatchMeasurement) -> BatchOutput:
        A_deg, w_deg = m.A_bd / DEG, m.omega_e / DEG
        finite = np.all(np.isfinite(A_deg) & np.isfinite(w_deg), 1)[:, None]
        integral_next = self.integral + A_deg * self.control_period
        raw = -((self.kp * A_deg + self.ki * integral_next) + self.kd * w_deg)
        saturated = np.abs(raw) > self.torque_limit
        self.integral = np.where(finite & ~saturated, integral_next, self.integral)
        torque = np.where(finite, np.clip(raw, -self.torque_limit, self.torque_limit), 0.0)
        return BatchOutput(torque=torque, saturated=np.any(saturated, 1) & finite[:, 0])


def make_pid_batch(*, torque_limit: float, control_period: float, gains: PidGains = TABLE1_GAINS) -> PidBatch:
    return PidBatch(GainSets.of(gains), torque_limit, control_period)
