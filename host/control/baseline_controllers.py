"""The two fitted baselines (host.control.baselines) flown in the closed loop, as the PID and the
network are: the controller preprocesses its measurement (host.gnc.preprocess: the same noisy
inputs the network sees), evaluates the law on S_in in Table 2 units and clips to the wheel limit.

* "pdff": the saturated PD + feed-forward law (paper-style PD on A_bd, ω_e plus I·ω̇_d + ω_d × I·ω_d);
* "linear": the least-squares linear law on the 12 inputs.

Both come from a baselines file written next to the trained artifact (`staregen train` ->
<artifact>.baselines.json, the pipeline -> network.baselines.json).
"""
from __future__ import annotations

import functools

import numpy as np

from host.control.baselines import LinearLS, SaturatedLinear, load_baselines
from host.control.batch import BatchLayout, BatchMeasurement, BatchOutput
from host.control.controllers import ControlOutput, Measurement
from host.control.nn_controller import clip_torque
from host.errors import HostError
from host.gnc.preprocess import preprocess


class BaselineController:
    def __init__(self, name: str, law: LinearLS | SaturatedLinear, torque_limit: float):
        self.name, self.law, self.torque_limit = name, law, float(torque_limit)

    def reset(self) -> None:
        """Stateless."""

    def step(self, m: Measurement) -> ControlOutput:
        with np.errstate(all="ignore"):
            x = preprocess(m)
            raw = self.law.predict(x.network_inputs_deg()[None, :])[0]
        return ControlOutput(torque=clip_torque(raw, self.torque_limit), mode=self.name,
                             info={"A_bd": x.A_bd, "omega_e": x.omega_e})


class BaselineBatch:
    """BaselineController on rows."""

    variants = 1

    def __init__(self, name: str, law: LinearLS | SaturatedLinear, torque_limit: float):
        self.name, self.law, self.torque_limit = name, law, float(torque_limit)

    def reset(self, layout: BatchLayout) -> None:
        """Stateless."""

    def step(self, m: BatchMeasurement) -> BatchOutput:
        with np.errstate(all="ignore"):
            raw = self.law.predict(m.network_inputs_deg())
        torque = clip_torque(raw, self.torque_limit)
        return BatchOutput(torque=torque, saturated=np.any(torque != raw, 1))


@functools.lru_cache(maxsize=4)
def _laws(path: str):
    return load_baselines(path)


def _law(name: str, baselines: str | None) -> LinearLS | SaturatedLinear:
    if baselines is None:
        raise HostError(f"controller {name} needs --baselines FILE (written by `staregen train` next to the "
                        "artifact, or network.baselines.json in a pipeline folder)")
    linear, pdff = _laws(str(baselines))
    return pdff if name == "pdff" else linear


def _make(name: str, torque_limit: float, baselines: str | None) -> BaselineController:
    return BaselineController(name, _law(name, baselines), torque_limit)


def make_pdff_controller(*, torque_limit: float, control_period: float, baselines: str | None = None):
    return _make("pdff", torque_limit, baselines)


def make_linear_controller(*, torque_limit: float, control_period: float, baselines: str | None = None):
    return _make("linear", torque_limit, baselines)


def make_pdff_batch(*, torque_limit: float, control_period: float, baselines: str | None = None):
    return BaselineBatch("pdff", _law("pdff", baselines), torque_limit)


def make_linear_batch(*, torque_limit: float, control_period: float, baselines: str | None = None):
    return BaselineBatch("linear", _law("linear", baselines), torque_limit)
