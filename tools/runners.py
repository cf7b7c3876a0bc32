"""Run any generated unit on any target: the golden model, x86-64 (SIL, cffi) or the STM32F417
ELF in the Cortex-M4 emulator (PIL) — one runner per target, built from the unit's dtypes.

Every runner has the same three operations on the unit's structured records:
    records(batch)       N independent steps from the states in the batch -> (outputs, states after)
    reset()              the carried state back to <entry>_init
    sequence(inputs)     consecutive steps from the carried state (carried on afterwards)

Records cross to the C as raw bytes: { state before; input } in, { output; state after } out.
Both the cffi wrapper and the ARM adapters are generated here from the unit's dtypes (never
typed by hand per unit), and both carry compile-time checks that sizeof / offsetof of every C
struct field equal the numpy dtype's, so a dtype that drifts from its C struct fails the build.
"""
from __future__ import annotations

import numpy as np

from codegen.unit import Batch, Unit
from firmware import arm, x86
from tools.errors import ToolError
from tools.m4.elf import Image
from tools.m4.harness import Harness
from tools.m4.profile import Profiler

TARGETS = ("golden", "x86", "arm")
LAYOUT_FILE = "_unit_layout.c"   # sorts first: a drifted dtype fails the build before any other compile


# ----------------------------------------------------------------------------- record layout

def record_dtypes(unit: Unit) -> tuple[np.dtype, np.dtype]:
    """(in, out) record dtypes: {state; input} and {output; state} (no state when stateless)."""
    if unit.stateful:
        return (np.dtype([("state", unit.state_dtype), ("input", unit.input_dtype)]),
                np.dtype([("output", unit.output_dtype), ("state", unit.state_dtype)]))
    return np.dtype([("input", unit.input_dtype)]), np.dtype([("output", unit.output_dtype)])


def pack(unit: Unit, batch: Batch) -> np.ndarray:
    """A Batch as input records."""
    rec_in, _ = record_dtypes(unit)
    rec = np.zeros(batch.input.shape[0], dtype=rec_in)
    rec["input"] = batch.input
    if unit.stateful:
        if batch.state is None or batch.state.shape != batch.input.shape:
            raise ToolError(f"unit {unit.kind}: every input row needs a state row")
        rec["state"] = batch.state
    return rec


def unpack(unit: Unit, raw: np.ndarray) -> tuple[np.ndarray, np.ndarray | None]:
    """Output records (any buffer of them) -> (outputs, states after)."""
    _, rec_out = record_dtypes(unit)
    out = np.ascontiguousarray(raw).view(rec_out).reshape(-1)
    return out["output"].copy(), (out["state"].copy() if unit.stateful else None)


def _checks(ctype: str, dtype: np.dtype) -> list[str]:
    """C constant expressions that hold when the C type has the dtype's layout."""
    checks = [f"sizeof({ctype}) == {dtype.itemsize}u"]
    if "[" not in ctype:   # a struct: every field where numpy puts it
        checks += [f"offsetof({ctype}, {name}) == {dtype.fields[name][1]}u" for name in dtype.names]
    return checks


def layout_checks(unit: Unit) -> list[str]:
    types = unit.c_types
    roles = {"input": unit.input_dtype, "output": unit.output_dtype}
    if unit.stateful:
        roles["state"] = unit.state_dtype
    checks = [c for role, dt in roles.items() for c in _checks(types[role], dt)]
    for stage in unit.stages.values():
        checks += _checks(stage.c_input, stage.input) + _checks(stage.c_output, stage.output)
    return list(dict.fromkeys(checks))


# ----------------------------------------------------------------------------- golden

class GoldenRunner:
    """The unit's numpy golden model behind the runner interface."""

    target = "golden"

    def __init__(self, unit: Unit):
        self.unit = unit
        self.state = unit.init_state(1)

    def records(self, batch: Batch):
        return self.unit.golden(batch.state, batch.input)

    def reset(self) -> None:
        self.state = self.unit.init_state(1)

    def sequence(self, inputs: np.ndarray) -> np.ndarray:
        out = np.zeros(inputs.shape[0], dtype=self.unit.output_dtype)
        for t in range(inputs.shape[0]):
            out[t:t + 1], self.state = self.unit.golden(self.state, inputs[t:t + 1])
        return out


# ----------------------------------------------------------------------------- x86 (SIL)

CDEF = """
void sg_unit_records(const void *in, void *out, size_t n);
void sg_unit_sequence(void *state, const void *in, void *out, size_t n);
void sg_unit_init(void *state);
"""


def x86_cdef(unit: Unit) -> str:
    return CDEF + "".join(f"void sg_stage_{name}(const void *in, void *out, size_t n);\n" for name in unit.stages)


def x86_harness(unit: Unit) -> str:
    """Batch loops around the flight functions (the arithmetic stays in the flight objects)."""
    i_sz, o_sz = unit.input_dtype.itemsize, unit.output_dtype.itemsize
    s_sz = unit.state_dtype.itemsize if unit.stateful else 0
    if unit.stateful:
        call = f"{unit.step_symbol}((void *)(b + {o_sz}u), (const void *)(a + {s_sz}u), (void *)b)"
        seq = f"{unit.step_symbol}(state, (const void *)(x + r * {i_sz}u), (void *)(y + r * {o_sz}u))"
        init = f"{unit.init_symbol}(state)"
    else:
        call = f"{unit.step_symbol}((const void *)a, (void *)b)"
        seq = f"{unit.step_symbol}((const void *)(x + r * {i_sz}u), (void *)(y + r * {o_sz}u))"
        init = "(void)state"
    lines = ["#include <stddef.h>", "#include <string.h>", f'#include "{unit.header}"']
    lines += ["", "static void sg_unit_records(const void *in, void *out, size_t n)", "{", "    size_t r;",
              "    for (r = 0; r < n; ++r) {",
              f"        const unsigned char *a = (const unsigned char *)in + r * {s_sz + i_sz}u;",
              f"        unsigned char *b = (unsigned char *)out + r * {o_sz + s_sz}u;"]
    if unit.stateful:
        lines.append(f"        memcpy(b + {o_sz}u, a, {s_sz}u);")
    lines += [f"        {call};", "    }", "}", "",
              "static void sg_unit_sequence(void *state, const void *in, void *out, size_t n)", "{",
              "    const unsigned char *x = (const unsigned char *)in;", "    unsigned char *y = (unsigned char *)out;",
              "    size_t r;", "    (void)state;", "    for (r = 0; r < n; ++r) {", f"        {seq};", "    }", "}", "",
              "static void sg_unit_init(void *state)", "{", f"    {init};", "}"]
    for name, st in unit.stages.items():
        a, b = st.input.itemsize, st.output.itemsize
        lines += ["", f"static void sg_stage_{name}(const void *in, void *out, size_t n)", "{", "    size_t r;",
                  "    for (r = 0; r < n; ++r) {",
                  f"        {st.symbol}((const void *)((const unsigned char *)in + r * {a}u), "
                  f"(void *)((unsigned char *)out + r * {b}u));", "    }", "}"]
    return "\n".join(lines) + "\n"


def _ptr(ffi, a: np.ndarray):
    return ffi.cast("void *", ffi.from_buffer(a))


def layout_source(unit: Unit) -> str:
    """A C file that compiles only if every C struct has the layout of the unit's numpy dtype."""
    lines = ["/* Record layout checks of the unit (numpy dtype == C struct); generated by tools/runners.py. */",
             "#include <stddef.h>", f'#include "{unit.header}"', ""]
    for k, check in enumerate(layout_checks(unit)):
        lines.append(f"typedef char sg_layout_{k}[({check}) ? 1 : -1]; /* {check} */")
    return "\n".join(lines) + "\n"


class X86Runner:
    """The unit's C compiled with the flight flags for x86-64 and loaded through cffi (cached)."""

    target = "x86"

    def __init__(self, unit: Unit):
        self.unit = unit
        sources = {**unit.sources(), LAYOUT_FILE: layout_source(unit)}
        self.build = x86.build(sources, x86_cdef(unit), x86_harness(unit))
        self.ffi, self.lib = self.build.ffi, self.build.lib
        self.state = unit.init_state(1) if unit.stateful else np.zeros(1, np.uint32)
        self.reset()

    def records(self, batch: Batch):
        rec = pack(self.unit, batch)
        _, rec_out = record_dtypes(self.unit)
        out = np.zeros(rec.shape[0], dtype=rec_out)
        self.build.check_fp_environment()
        self.lib.sg_unit_records(_ptr(self.ffi, rec), _ptr(self.ffi, out), rec.shape[0])
        return unpack(self.unit, out)

    def reset(self) -> None:
        self.lib.sg_unit_init(_ptr(self.ffi, self.state))

    def sequence(self, inputs: np.ndarray) -> np.ndarray:
        inputs = np.ascontiguousarray(inputs, dtype=self.unit.input_dtype)
        out = np.zeros(inputs.shape[0], dtype=self.unit.output_dtype)
        self.build.check_fp_environment()
        self.lib.sg_unit_sequence(_ptr(self.ffi, self.state), _ptr(self.ffi, inputs), _ptr(self.ffi, out),
                                  inputs.shape[0])
        return out

    def stage(self, name: str, inp: np.ndarray) -> np.ndarray:
        """A stateless stage (e.g. the network's normalise) on input records of its dtype."""
        st = self.unit.stages[name]
        inp = np.ascontiguousarray(inp, dtype=st.input)
        out = np.zeros(inp.shape[0], dtype=st.output)
        self.build.check_fp_environment()
        getattr(self.lib, f"sg_stage_{name}")(_ptr(self.ffi, inp), _ptr(self.ffi, out), inp.shape[0])
        return out


# ----------------------------------------------------------------------------- ARM (PIL)

def adapter_params(unit: Unit) -> dict:
    return {"entry": unit.entry, "header": unit.header, "step": unit.step_symbol, "init": unit.init_symbol or "",
            "layout_checks": layout_checks(unit), "input_words": unit.input_dtype.itemsize // 4,
            "output_words": unit.output_dtype.itemsize // 4,
            "state_words": unit.state_dtype.itemsize // 4 if unit.stateful else 0}


def arm_build(unit: Unit, adapter: str = "records", opt: str = "-O2") -> arm.ArmBuild:
    """The unit's ELF with the `records` adapter (state in every record) or, for a stateful unit,
    the `sequence` adapter (state kept in the firmware between records)."""
    if adapter == "sequence" and not unit.stateful:
        adapter = "records"   # a stateless unit's sequence is its records
    return arm.build(unit.sources(), arm.render_adapter(adapter, **adapter_params(unit)), opt,
                     tables=unit.tables_in)


class ArmRunner:
    """The unit's STM32F417 ELF in the emulator. With cycles=True the sequence build runs under the
    cycle profiler and `cycles` holds the ideal-memory cycles of every step (PIL)."""

    target = "arm"

    def __init__(self, unit: Unit, cycles: bool = False):
        self.unit = unit
        self._records: Harness | None = None
        self.profiler = None
        image = Image(arm_build(unit, "sequence").elf)
        if cycles:
            self.profiler = Profiler(image, unit.step_symbol, memory_modes=False)
        self._sequence = Harness(image, machine=self.profiler.machine if cycles else None,
                                 max_insns_per_record=unit.max_instructions)
        self.cycles: list[int] = []
        self.reset()

    @property
    def _runner(self):
        return self.profiler.run if self.profiler else None

    def records(self, batch: Batch):
        if self._records is None:
            self._records = Harness(arm_build(self.unit, "records").elf,
                                    max_insns_per_record=self.unit.max_instructions)
        rec = pack(self.unit, batch)
        return unpack(self.unit, self._records.run(rec.view(np.uint8).reshape(rec.shape[0], -1)))

    def reset(self) -> None:
        if self.unit.stateful:
            self._sequence.reset(runner=self._runner)

    def sequence(self, inputs: np.ndarray) -> np.ndarray:
        """Consecutive steps (a stateless unit's sequence build is its records build)."""
        inputs = np.ascontiguousarray(inputs, dtype=self.unit.input_dtype)
        raw = self._sequence.run(inputs.view(np.uint8).reshape(inputs.shape[0], -1), runner=self._runner)
        if self.profiler is not None:
            self.cycles += [int(ev.total[0]) for ev in self.profiler.evaluations]
            self.profiler.evaluations.clear()
        return raw.view(self.unit.output_dtype).reshape(inputs.shape[0]).copy()


def runner(unit: Unit, target: str, cycles: bool = False):
    """A ready runner of `unit` on `target` (golden, x86 or arm); builds are cached."""
    if target == "golden":
        return GoldenRunner(unit)
    if target == "x86":
        return X86Runner(unit)
    if target == "arm":
        return ArmRunner(unit, cycles=cycles)
    raise ToolError(f"unknown target {target!r} (choose from {', '.join(TARGETS)})")

