"""The on-board controller interface every controller implements (PID now; NN, generated C via
SIL/PIL and the tanh law in later issues), and the registry the CLI builds controllers from.

Each control period the simulator hands the controller a Measurement (the inputs of paper 001
Fig. 2, SI units) and applies the returned torque, held for one period (zero-order hold).
A controller computes its own desired state from the measurement (host.gnc.preprocess).
"""
from __future__ import annotations

import importlib
from dataclasses import dataclass, field
from typing import Protocol

import numpy as np

from host.errors import HostError


@dataclass(frozen=True)
class Measurement:
    """What the on-board controller receives each control period, SI units."""
    t: float                # s since the scenario epoch
    jd_days: int            # UTC split as in host.core.timebase: JD = jd_days - 0.5 + sec_of_day/86400
    sec_of_day: float
    A_bo: np.ndarray        # measured Euler 3-1-2 of body w.r.t. orbital frame, rad (star sensor)
    omega_b: np.ndarray     # measured body rate w.r.t. inertial, body axes, rad/s (gyro)
    R_s: np.ndarray         # ECI position, m (GPS)
    V_s: np.ndarray         # ECI velocity, m/s (GPS)
    lon: float              # target geodetic longitude, rad (telecommand)
    lat: float              # target geodetic latitude, rad


@dataclass(frozen=True)
class ControlOutput:
    torque: np.ndarray                      # (3,) commanded wheel torque on the body, N·m, body axes
    mode: str                               # which law produced it, e.g. "pid", "nn"
    info: dict = field(default_factory=dict)  # diagnostics (e.g. the controller's A_bd, ω_e)


class Controller(Protocol):
    name: str

    def reset(self) -> None: ...

    def step(self, m: Measurement) -> ControlOutput: ...


# name -> "module:factory"; factory(torque_limit=..., control_period=...) -> Controller.
# Later issues add their controllers here.
CONTROLLERS = {
    "pid": "host.control.pid:make_pid_controller",
    "nn": "host.control.nn_controller:make_nn_controller",
    "nn-c": "host.control.generated_controller:make_sil_controller",
    "pid-c": "host.control.generated_controller:make_sil_pid_controller",
    "nn-arm": "host.control.generated_controller:make_pil_controller",
    "pdff": "host.control.baseline_controllers:make_pdff_controller",
    "linear": "host.control.baseline_controllers:make_linear_controller",
    "dp": "host.control.dp_controller:make_dp_controller",
    "dp-c": "host.control.dp_controller:make_dp_sil_controller",
}
# name -> "module:factory" of the batched form (host.control.batch: the same law on rows), for
# every controller that has one; the batched simulator (host.sim.batched) flies these. The PIL run
# (nn-arm) has none: the ARM emulator steps one record at a time.
BATCH_CONTROLLERS = {
    "pid": "host.control.pid:make_pid_batch",
    "nn": "host.control.nn_controller:make_nn_batch",
    "nn-c": "host.control.generated_controller:make_sil_batch",
    "pid-c": "host.control.generated_controller:make_sil_pid_batch",
    "pdff": "host.control.baseline_controllers:make_pdff_batch",
    "linear": "host.control.baseline_controllers:make_linear_batch",
    "dp": "host.control.dp_controller:make_dp_batch",
    "dp-c": "host.control.dp_controller:make_dp_sil_batch",
}
# Controllers built from a model artifact accept `artifact=` (a file path, None = the stand-in).
ARTIFACT_CONTROLLERS = ("nn", "nn-c", "pid-c", "nn-arm")
# The fitted baselines accept `baselines=` (a baselines file written by `staregen train`).
BASELINE_CONTROLLERS = ("pdff", "linear")
# The discrete-point controllers accept `tables=` (a tables file written by `staregen dp build`).
DP_CONTROLLERS = ("dp", "dp-c")


def _build(registry: dict, name: str, torque_limit: float, control_period: float, options: dict):
    if name not in registry:
        raise HostError(f"unknown controller {name!r} (known: {', '.join(sorted(registry))})")
    module, factory = registry[name].split(":")
    return getattr(importlib.import_module(module), factory)(
        torque_limit=torque_limit, control_period=control_period, **options)


def build_controller(name: str, *, torque_limit: float, control_period: float, **options) -> Controller:
    """Instantiate a registered controller by name; unknown names are a user error.
    `options` go to the factory (e.g. artifact= for ARTIFACT_CONTROLLERS)."""
    return _build(CONTROLLERS, name, torque_limit, control_period, options)


def has_batch(name: str) -> bool:
    return name in BATCH_CONTROLLERS


def build_batch_controller(name: str, *, torque_limit: float, control_period: float, **options):
    """The batched form (host.control.batch.BatchController) of a registered controller."""
    return _build(BATCH_CONTROLLERS, name, torque_limit, control_period, options)
