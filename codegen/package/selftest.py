"""The flight package's on-target self-test: golden vectors of every unit as hex words in C.

For each unit, N vectors drawn from its gate classes (every class present, in the gate's
proportions; vector 0 is the first class's, the timing reference) are run through the golden
model; the C holds {state in, input, expected output, expected state out} as uint32 words and
`int <name>_selftest(void)` replays them through the flight step, counting mismatching words,
every bit compared (NaN outputs are canonical on every target). Five floating-point environment
checks (subnormal results kept, subnormal operands not read as zero, round to nearest in both
directions, no fused multiply-add in the self-test's own translation unit) add one each when they
fail, so a board whose start-up code set flush-to-zero (FPSCR.FZ, MXCSR.FTZ), denormals-are-zero
(MXCSR.DAZ) or a directed rounding mode fails the self-test even where the vectors would not show
it. FPSCR.DN (default NaN) is not checked: it changes NaN payloads only, and the outputs do not
depend on it (tests/tools/test_package_integrity.py, over the gate classes and random bits).
"""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from codegen import GENERATOR_VERSION
from codegen.cgen import check_name, environment
from codegen.errors import CodegenError
from codegen.unit import Unit, words

TEMPLATES = Path(__file__).with_name("templates")
DEFAULT_VECTORS = 256
MAX_VECTORS = 4096


@dataclass(frozen=True)
class SelftestVectors:
    """N golden steps of one unit: state before (None if stateless), input, output, state after."""

    unit: Unit
    state: np.ndarray | None
    input: np.ndarray
    output: np.ndarray
    state_after: np.ndarray | None
    classes: dict[str, int]          # class name -> vectors, in order

    @property
    def n(self) -> int:
        return int(self.input.shape[0])


def make_vectors(unit: Unit, n: int = DEFAULT_VECTORS, seed: int = 0) -> SelftestVectors:
    """n vectors from the unit's gate classes (deterministic in seed) with their golden results;
    vector 0 starts from the init state (the timing reference)."""
    if not 1 <= n <= MAX_VECTORS:
        raise CodegenError(f"self-test vectors must be in [1, {MAX_VECTORS}], got {n}")
    classes = {c: b for c, b in unit.gate_classes(n, seed).items() if b.input.shape[0] > 0}
    inputs = np.concatenate([b.input for b in classes.values()])
    state = np.concatenate([b.state for b in classes.values()]) if unit.stateful else None
    if state is not None:
        state[0] = unit.init_state(1)[0]   # the reference: the first step after init on a first-class input
    out, after = unit.golden(None if state is None else state.copy(), inputs)
    return SelftestVectors(unit, state, inputs, out, after, {c: int(b.input.shape[0]) for c, b in classes.items()})


def _rows(v: SelftestVectors) -> list[list[str]]:
    parts = [words(v.input), words(v.output)]
    if v.unit.stateful:
        parts = [words(v.state)] + parts + [words(v.state_after)]
    table = np.concatenate(parts, axis=1)
    return [[f"0x{w:08x}u" for w in row] for row in table]


def field_elements(dtype: np.dtype) -> list[str]:
    """Every scalar element of a record as a C lvalue suffix: "integral[0]", ..., "mode"."""
    out = []
    for name in dtype.names:
        shape = dtype.fields[name][0].shape
        out += [f"{name}[{i}]" for i in range(shape[0])] if shape else [name]
    return out


def _unit_context(v: SelftestVectors) -> dict:
    u = v.unit
    st = u.state_dtype
    return {
        "entry": u.entry, "kind": u.kind, "header": u.header, "step": u.step_symbol, "stateful": u.stateful,
        "n": v.n, "classes": v.classes,
        "input_t": u.c_types["input"], "output_t": u.c_types["output"],
        "state_t": u.c_types.get("state", ""),
        "input_words": u.input_dtype.itemsize // 4, "output_words": u.output_dtype.itemsize // 4,
        "state_words": st.itemsize // 4 if st is not None else 0,
        "rows": _rows(v),
        "input_fields": field_elements(u.input_dtype),
        "state_fields": field_elements(st) if st is not None else [],
    }


def selftest_sources(name: str, vectors: list[SelftestVectors]) -> dict[str, str]:
    """{"<name>_selftest.h": ..., "<name>_selftest.c": ...}; vectors[0] is the reference unit
    (the controller), whose vector 0 `<name>_selftest_reference` hands out."""
    check_name(name)
    if not vectors or not vectors[0].unit.stateful:
        raise CodegenError("the self-test's first unit must be the stateful controller (its reference step)")
    for v in vectors:
        if "[" in v.unit.c_types["input"] or "[" in v.unit.c_types["output"]:
            raise CodegenError(f"self-test: unit {v.unit.kind} exchanges arrays, not structs")
    ctx = {"name": name, "P": name.upper(), "generator_version": GENERATOR_VERSION,
           "units": [_unit_context(v) for v in vectors], "ref": _unit_context(vectors[0])}
    env = environment(TEMPLATES)
    return {f"{name}_selftest.h": env.get_template("selftest.h.j2").render(ctx),
            f"{name}_selftest.c": env.get_template("selftest.c.j2").render(ctx)}
