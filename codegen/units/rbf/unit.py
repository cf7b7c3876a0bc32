"""Paper 002's RBF adaptive finite-time backstepping law (docs/rbf-backstepping.md section 11) as a
generated unit: state {theta, theta_delta, command} (the weights, adapted on board, and the last output
normalised, the second network's input), input {the measured and
desired line of sight and attitude with their derivatives}, output {force, torque, w_hat, status};
parameters and control period baked in as float32 constants.
"""
from __future__ import annotations

import numpy as np

from codegen.errors import CodegenError
from codegen.unit import Batch, Budgets, Unit
from codegen.units.rbf import golden, interface, records, vectors
from codegen.units.rbf.emit import DEFAULT_NAME, DEFAULT_PERIOD, check_period, constants32, params_sha256, rbf_sources
from codegen.units.rbf.params import RbfParams

# SPEC section 8: the theorem-2 step at the default 7 nodes, ideal memory (measured 2026-11-27 with the
# command input: static bound 5,734). RAM: the constant tables copied to CCM (3,200 B, the power table 3,080
# of them) + the caller-owned state (weights 336 B at 7 nodes, command 24 B), measured 3,560 B; stack
# measured 448 B (SPEC's 512 B for the whole controller is the ceiling). Flash: code + tables of rbf.o and
# sg_math.o, measured 11,592 B; 16 KB leaves the whole controller's 24 KB of SPEC section 8 for the rest.
BUDGETS = Budgets(cycles=6_000, flash=16_384, ram=4_096, stack=512)
STATUS_NAMES = ((records.STATUS_INVALID_INPUT, "invalid"), (records.STATUS_FORCE_LIMITED, "force limited"),
                (records.STATUS_TORQUE_LIMITED, "torque limited"), (records.STATUS_WEIGHT_BOUND, "weight bound"),
                (records.STATUS_STATE_REPAIRED, "state repaired"))


class RbfUnit(Unit):
    kind = "rbf"

    def __init__(self, params: RbfParams, period: float = DEFAULT_PERIOD, name: str = DEFAULT_NAME):
        self.params, self.period = params, check_period(period)
        self.constants = constants32(params, self.period)
        self._sources = rbf_sources(params, self.period, name)
        super().__init__(name, records.INPUT_DTYPE, records.OUTPUT_DTYPE, records.state_dtype(params.nodes), BUDGETS)

    def identity(self) -> str:
        return (f"rbf law ({self.step_symbol}), theorem {self.params.theorem}, {self.params.nodes} nodes, period "
                f"{self.period:g} s, params sha256 {params_sha256(self.params, self.period)[:16]}")

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
        return vectors.gate_sequences(self.constants, n_seq, steps, seed, self.period)

    def cycle_classes(self, per_class: int, seed: int) -> dict[str, Batch]:
        classes = vectors.gate_classes(self.constants, per_class * len(vectors.CLASSES), seed)
        return {c: Batch(b.state[:per_class], b.input[:per_class]) for c, b in classes.items()}

    def check_outputs(self, out: np.ndarray) -> list[str]:
        problems = []
        for name in ("force", "torque", "w_hat"):
            if not np.all(np.isfinite(out[name])):
                problems.append(f"non-finite {name}")
        if np.any(np.abs(out["force"]) > np.float32(self.params.force_max)):
            problems.append(f"|force| above force_max = {self.params.force_max:g} N")
        if np.any(np.abs(out["torque"]) > np.float32(self.params.torque_max)):
            problems.append(f"|torque| above torque_max = {self.params.torque_max:g} N*m")
        return problems

    def check_state(self, state: np.ndarray) -> list[str]:
        """Every weight finite and within its column's bound; every command entry finite and in [-1, 1]."""
        bound = self.constants.theta_max
        problems = []
        for name in ("theta", "theta_delta"):
            w = np.asarray(state[name]).reshape(-1, self.params.nodes, 6)
            if not np.all(np.isfinite(w)):
                problems.append(f"non-finite {name}")
            elif np.any(np.abs(w) > bound):
                problems.append(f"{name} beyond its bound")
        u = np.asarray(state["command"])
        if not np.all(np.isfinite(u)):
            problems.append("non-finite command")
        elif np.any(np.abs(u) > np.float32(1.0)):
            problems.append("command beyond [-1, 1]")
        return problems

    def describe_outputs(self, out: np.ndarray) -> str:
        s = out["status"].reshape(-1)
        return "status: ok " + str(int((s == 0).sum())) + ", " + ", ".join(
            f"{name} {int(((s & bit) != 0).sum())}" for bit, name in STATUS_NAMES)


def configure(params: RbfParams | None = None, period: float | None = None, name: str | None = None,
              **_ignored) -> RbfUnit:
    if params is None:
        raise CodegenError("unit rbf needs --params FILE (e.g. docs/rbf_paper002.toml)")
    if not isinstance(params, RbfParams):
        raise CodegenError(f"unit rbf: params must be RbfParams, got {type(params).__name__}")
    return RbfUnit(params, DEFAULT_PERIOD if period is None else period, name or DEFAULT_NAME)
