"""The satlin unit: stateless, input {x[3]}, output {u[3]}, gate classes inside / outside / special."""
from pathlib import Path

import numpy as np

from codegen import GENERATOR_VERSION
from codegen.cgen import c_float, check_name, environment
from codegen.unit import Batch, Budgets, Unit
from tests.tools.throwaway_unit import golden

TEMPLATES = Path(__file__).with_name("templates")
K = np.array([[1.5, -0.25, 0.0], [0.125, 2.0, 0.5], [-1.0, 0.0, 0.75]], dtype=np.float32)
LIMIT = np.float32(1.0)
SPECIAL = np.array([0.0, -0.0, 1e-45, np.inf, -np.inf, np.nan, 3.4028235e38], dtype=np.float32)


class SatlinUnit(Unit):
    kind = "satlin"

    def __init__(self, name: str = "satlin"):
        super().__init__(check_name(name), np.dtype([("x", "<f4", (3,))]), np.dtype([("u", "<f4", (3,))]), None,
                         Budgets(cycles=200, flash=1024, ram=64, stack=64))

    def sources(self) -> dict[str, str]:
        env = environment(TEMPLATES)
        ctx = {"name": self.entry, "P": self.entry.upper(), "generator_version": GENERATOR_VERSION,
               "k": [[c_float(v) for v in row] for row in K], "limit": c_float(LIMIT)}
        return {f"{self.entry}.h": env.get_template("satlin.h.j2").render(ctx),
                f"{self.entry}.c": env.get_template("satlin.c.j2").render(ctx)}

    def golden(self, state, inp):
        if inp.dtype != self.input_dtype:
            raise ValueError(f"golden satlin: expected {self.input_dtype} records, got {inp.dtype}")
        out = np.zeros(inp.shape[0], dtype=self.output_dtype)
        out["u"] = golden.step(K, LIMIT, np.ascontiguousarray(inp["x"]))
        return out, None

    def gate_classes(self, n: int, seed: int) -> dict[str, Batch]:
        rng = np.random.default_rng(seed)
        third = n // 3
        x = {"inside": rng.uniform(-0.3, 0.3, (n - 2 * third, 3)), "outside": rng.uniform(-50, 50, (third, 3)),
             "special": SPECIAL[rng.integers(0, SPECIAL.size, (third, 3))]}
        out = {}
        for c, v in x.items():
            rec = np.zeros(v.shape[0], dtype=self.input_dtype)
            rec["x"] = v.astype(np.float32)
            out[c] = Batch(None, rec)
        return out


def configure(name: str | None = None, **_ignored) -> SatlinUnit:
    return SatlinUnit(name or "satlin")
