"""The one in-the-loop runner: a generated unit stepped once per control period by a simulator.

SIL (x86 through cffi) or PIL (the ARM ELF in the emulator, with the cycles of every step), with
the golden model stepping alongside from its own state: each step's output and state are
compared bit for bit, so a closed-loop run is also a gate. The simulator packs its measurement
into the unit's input record and reads the output record; nothing here knows the simulator.
"""
from __future__ import annotations

import numpy as np

from codegen.unit import Unit
from tools.gate import compare_fields
from tools.runners import GoldenRunner, runner


class InTheLoop:
    def __init__(self, unit: Unit, target: str, golden_twin: bool = True):
        self.unit, self.target = unit, target
        self.run = runner(unit, target, cycles=target == "arm")
        self.twin = GoldenRunner(unit) if golden_twin and target != "golden" else None
        self.reset()

    def reset(self) -> None:
        self.run.reset()
        if self.twin is not None:
            self.twin.reset()
        if hasattr(self.run, "cycles"):
            self.run.cycles.clear()
        self.inputs: list[np.ndarray] = []
        self.outputs: list[np.ndarray] = []
        self.states: list[np.ndarray] = []     # the golden state before each step (twin or golden target)
        self.mismatch_steps = 0

    @property
    def cycles(self) -> list[int]:
        """Ideal-memory cycles of each step (PIL only; empty otherwise)."""
        return list(getattr(self.run, "cycles", []))

    def step(self, inp: np.ndarray) -> np.ndarray:
        """One step: inp is one input record (shape (1,)); returns the output record (shape (1,))."""
        inp = np.ascontiguousarray(inp, dtype=self.unit.input_dtype).reshape(1)
        reference = self.twin if self.twin is not None else self.run
        if self.unit.stateful and isinstance(reference, GoldenRunner):
            self.states.append(reference.state.copy())
        out = self.run.sequence(inp)
        if self.twin is not None:
            expected = self.twin.sequence(inp)
            self.mismatch_steps += int(bool(compare_fields(expected, out)))
        self.inputs.append(inp)
        self.outputs.append(out)
        return out

    def trace(self) -> tuple[np.ndarray, np.ndarray]:
        """(inputs (T,), outputs (T,)) of every step so far."""
        return np.concatenate(self.inputs), np.concatenate(self.outputs)

    def state_records(self) -> np.ndarray | None:
        """(T,) states before each step (the golden twin's, equal to the C's while mismatch_steps is 0)."""
        return np.concatenate(self.states) if self.states else None

