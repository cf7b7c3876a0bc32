"""The discrete-point controller of seed paper 003 as a generated unit: stateless, input {x[12]}
(Table 2 units), output {torque[3], found, used, level, status}; the samples and settings come from
a tables artifact (codegen/units/dp/tables.py)."""
from __future__ import annotations

import numpy as np

from codegen.errors import CodegenError
from codegen.unit import Batch, Budgets, Unit
from codegen.units.dp import golden, interface, vectors
from codegen.units.dp.emit import DEFAULT_NAME, dp_sources
from codegen.units.dp.tables import DpTables

# Judged against the paper's 3.3 ms on the STM32F417 at 168 MHz; flash: the tables' own budget.
BUDGETS = Budgets(cycles=554_400, cycles_art=554_400, flash=None, ram=None, stack=16 * 1024)
STATUS_NAMES = ((golden.STATUS_WIDENED, "widened"), (golden.STATUS_EVERY_SAMPLE, "every sample"),
                (golden.STATUS_SINGULAR, "singular"), (golden.STATUS_INVALID, "invalid"))


class DpUnit(Unit):
    kind = "dp"
    tables_in = "flash"               # up to 917 KB of samples: far more than the 64 KB of CCM
    max_instructions = 50_000_000     # the box scans and the fits: ~1e5-1e6 per step with 10,000 samples

    def __init__(self, tables: DpTables, name: str = DEFAULT_NAME):
        self.tables = tables
        self.constants = golden.Constants(tables)
        self._sources = dp_sources(tables, name)
        super().__init__(name, golden.INPUT_DTYPE, golden.OUTPUT_DTYPE, None, BUDGETS)

    def identity(self) -> str:
        p = self.tables.params
        return (f"discrete point ({self.step_symbol}), {self.tables.n} samples, r {p.r:g}, S_limit {p.s_limit}, "
                f"tables sha256 {self.tables.sha256[:16]}")

    def sources(self) -> dict[str, str]:
        return dict(self._sources)

    def field_docs(self):
        return interface.field_docs(self.tables)

    def status_bits(self):
        return interface.status_bits()

    def golden(self, state, inp):
        return golden.step(self.constants, inp), None

    def _batch(self, x: np.ndarray) -> Batch:
        rec = np.zeros(x.shape[0], dtype=self.input_dtype)
        rec["x"] = x
        return Batch(None, rec)

    def gate_classes(self, n: int, seed: int) -> dict[str, Batch]:
        return {name: self._batch(x) for name, x in vectors.gate_inputs(self.tables, n, seed).items()}

    def cycle_classes(self, per_class: int, seed: int) -> dict[str, Batch]:
        rows = vectors.gate_inputs(self.tables, per_class * 12, seed)
        return {name: self._batch(x[:per_class]) for name, x in rows.items()}

    def check_outputs(self, out: np.ndarray) -> list[str]:
        problems = []
        if not np.all(np.isfinite(out["torque"])):
            problems.append("non-finite torque")
        if np.any(out["used"] > self.tables.params.s_limit) or np.any(out["used"] > out["found"]):
            problems.append("used exceeds S_limit or found")
        return problems

    def describe_outputs(self, out: np.ndarray) -> str:
        s = out["status"]
        return "status: " + ", ".join(f"{name} {int(((s & bit) != 0).sum())}" for bit, name in STATUS_NAMES)


def configure(tables: DpTables | None = None, name: str | None = None, **_ignored) -> DpUnit:
    if tables is None:
        raise CodegenError("unit dp needs --tables FILE (written by `staregen dp build`)")
    return DpUnit(tables, name or DEFAULT_NAME)
