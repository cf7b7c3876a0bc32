"""Paper 000's finite-time tanh saturation law (eq. 17 with the auxiliary system 18-20) as a
generated unit: state {varpi}, input {R_c, w_c, R_t, w_t, wdot_t}, output {torque, x1, x2,
varpi, status}; parameters and control period baked in as float32 constants.
"""
from __future__ import annotations

import numpy as np

from codegen.errors import CodegenError
from codegen.units.tanh import interface
from codegen.unit import Batch, Budgets, Unit
from codegen.units.tanh import golden, vectors
from codegen.units.tanh.emit import (DEFAULT_NAME, DEFAULT_PERIOD, INPUT_DTYPE, OUTPUT_DTYPE, STATE_DTYPE,
                                     check_period, constants32, params_sha256, tanh_sources)
from codegen.units.tanh.params import TanhParams

# SPEC section 8 budget of the tanh-law step as this generator meets it (ideal memory).
BUDGETS = Budgets(cycles=1_200, flash=None, ram=None, stack=512)
STATUS_NAMES = ("ok", "singular", "invalid")


class TanhUnit(Unit):
    kind = "tanh"

    def __init__(self, params: TanhParams, period: float = DEFAULT_PERIOD,
                 scenario: vectors.ClosedLoop | None = None, name: str = DEFAULT_NAME):
        self.params, self.period, self.scenario = params, check_period(period), scenario
        self.constants = constants32(params, self.period)
        self._sources = tanh_sources(params, self.period, name)
        super().__init__(name, INPUT_DTYPE, OUTPUT_DTYPE, STATE_DTYPE, BUDGETS)

    def identity(self) -> str:
        return f"tanh law ({self.step_symbol}), period {self.period:g} s, params sha256 " \
               f"{params_sha256(self.params, self.period)[:16]}"

    def values_sha256(self) -> str:
        return params_sha256(self.params, self.period)

    def sources(self) -> dict[str, str]:
        return dict(self._sources)

    def field_docs(self):
        return interface.field_docs(self.params)

    def status_bits(self):
        return interface.status_bits()

    def golden(self, state, inp):
        return golden.step(self.constants, state, inp)

    def gate_classes(self, n: int, seed: int) -> dict[str, Batch]:
        return vectors.gate_classes(self.constants, n, seed)

    def gate_sequences(self, n_seq: int, steps: int, seed: int) -> np.ndarray:
        if self.scenario is None:
            return vectors.open_sequences(self.constants, n_seq, steps, seed)
        return self.scenario.sequences(self, n_seq, steps, seed)

    def cycle_classes(self, per_class: int, seed: int) -> dict[str, Batch]:
        classes = vectors.gate_classes(self.constants, per_class * len(vectors.CLASSES), seed)
        if self.scenario is not None:
            classes.update(self.scenario.cycle_classes(self))
        return classes

    def describe_outputs(self, out: np.ndarray) -> str:
        status = out["status"].reshape(-1)
        return "status: " + ", ".join(f"{name} {int((status == v).sum())}" for v, name in enumerate(STATUS_NAMES))


def configure(params: TanhParams | None = None, period: float | None = None, scenario=None, name: str | None = None,
              **_ignored) -> TanhUnit:
    if params is None:
        raise CodegenError("unit tanh needs --params FILE (e.g. docs/tanh_paper000.toml)")
    return TanhUnit(params, DEFAULT_PERIOD if period is None else period, scenario, name or DEFAULT_NAME)
