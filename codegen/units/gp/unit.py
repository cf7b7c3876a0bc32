"""Paper 004's sparse-GP takeover law (docs/gp-takeover.md section 11) as a generated unit: stateless,
input {q, omega, h_w}, output {torque, mu, var, gains, status}; the trained GP's arrays and the law's
constants baked in as float32 constants (codegen/units/gp/emit.py)."""
from __future__ import annotations

import numpy as np

from codegen.errors import CodegenError
from codegen.unit import Batch, Budgets, Unit
from codegen.units.gp import golden, interface, records, vectors
from codegen.units.gp.emit import DEFAULT_NAME, constants32, gp_sources
from codegen.units.gp.params import GpLawParams

# SPEC section 8 and issue 27: the default configuration (M = 20) within 15,000 cycles, ideal memory
# (static bound). Flash, RAM and stack: measured at M = 20 (docs/gp-takeover.md section 15) with margin.
BUDGETS = Budgets(cycles=15_000, flash=16_384, ram=8_192, stack=512)
STATUS_NAMES = ((records.STATUS_INVALID_INPUT, "invalid"), (records.STATUS_TORQUE_LIMITED, "torque limited"),
                (records.STATUS_VAR_FLOOR, "variance floor"), (records.STATUS_VAR_CEILING, "variance ceiling"))


class GpUnit(Unit):
    kind = "gp"

    def __init__(self, params: GpLawParams, name: str = DEFAULT_NAME):
        self.params = params
        self.constants = constants32(params)
        self._sources = gp_sources(params, name)
        super().__init__(name, records.INPUT_DTYPE, records.OUTPUT_DTYPE, None, BUDGETS)

    def identity(self) -> str:
        return (f"gp law ({self.step_symbol}), M = {self.params.n_inducing} inducing points, params sha256 "
                f"{self.params.sha256()[:16]}, artifact sha256 {self.params.gp.sha256[:16]}")

    def values_sha256(self) -> str:
        return self.params.sha256()

    def sources(self) -> dict[str, str]:
        return dict(self._sources)

    def field_docs(self):
        return interface.field_docs(self.params)

    def status_bits(self):
        return interface.status_bits()

    def golden(self, state, inp):
        return golden.step(self.constants, state, inp)

    def gate_classes(self, n: int, seed: int) -> dict[str, Batch]:
        return vectors.gate_classes(self.params, n, seed)

    def cycle_classes(self, per_class: int, seed: int) -> dict[str, Batch]:
        classes = vectors.gate_classes(self.params, per_class * len(vectors.CLASSES), seed)
        return {c: Batch(None, b.input[:per_class]) for c, b in classes.items()}

    def check_outputs(self, out: np.ndarray) -> list[str]:
        """Finite outputs; |torque| within its limit; the variance's sign bit clear and at most the prior;
        the gains within their bounds."""
        c = self.constants
        problems = [f"non-finite {name}" for name in ("torque", "mu", "var", "gains")
                    if not np.all(np.isfinite(out[name]))]
        if np.any(np.abs(out["torque"]) > c.torque_max):
            problems.append(f"|torque| above torque_max = {self.params.torque_max:g} N*m")
        var_bits = np.ascontiguousarray(out["var"]).view(np.uint32)
        if np.any(var_bits >> np.uint32(31)):
            problems.append("negative variance (sign bit set)")
        if np.any(out["var"] > c.prior_var):
            problems.append("variance above the prior")
        k1, k2 = out["gains"][:, 0], out["gains"][:, 1]
        if np.any((k1 < c.k1) | (k1 > c.k1_bar) | (k2 < c.k2) | (k2 > c.k2_bar)):
            problems.append("a gain outside its bounds")
        return problems

    def describe_outputs(self, out: np.ndarray) -> str:
        s = out["status"].reshape(-1)
        return "status: ok " + str(int((s == 0).sum())) + ", " + ", ".join(
            f"{name} {int(((s & bit) != 0).sum())}" for bit, name in STATUS_NAMES)


def configure(params: GpLawParams | None = None, name: str | None = None) -> GpUnit:
    """The unit bound to its law file (`--params docs/gp_paper004.toml`); the law is stateless and has no
    control period (its KIND says `takes_period=False`: the CLI refuses `--period`)."""
    if params is None:
        raise CodegenError("unit gp needs --params FILE (the law file naming the GP artifact, e.g. docs/gp_paper004.toml)")
    if not isinstance(params, GpLawParams):
        raise CodegenError(f"unit gp: params must be GpLawParams, got {type(params).__name__}")
    return GpUnit(params, name or DEFAULT_NAME)
