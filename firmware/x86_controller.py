"""x86-64 (SIL) build of the generated controller: cffi declarations, batch loops and a numpy API.

Two ways to run it, matching the two ARM adapters:
  * records: each row carries its own state in and out (independent steps from chosen states);
  * sequence: one state carried from row to row (a time series), or one step at a time (SIL).
Arrays are the structured dtypes of codegen.controller_emit (the C structs have no padding).
"""
from __future__ import annotations

import numpy as np

from codegen import controller_spec as cs
from codegen.artifact import Artifact
from codegen.controller_emit import (DEFAULT_NAME, INPUT_DTYPE, OUTPUT_DTYPE, RECORD_IN_DTYPE, RECORD_OUT_DTYPE,
                                     STATE_DTYPE, controller_sources)
from firmware import x86


def controller_cdef(name: str) -> str:
    return f"""
typedef struct {{ float A_bo[3]; float omega_b[3]; float R_s[3]; float V_s[3]; int32_t lon; int32_t lat;
                 int32_t utc_day; int32_t utc_ms; }} {name}_input_t;
typedef struct {{ float torque[3]; uint32_t status; float A_bd[3]; float omega_e[3]; }} {name}_output_t;
typedef struct {{ float integral[3]; uint32_t mode; uint32_t clean; }} {name}_state_t;
void {name}_init({name}_state_t *state);
void {name}_step({name}_state_t *state, const {name}_input_t *in, {name}_output_t *out);
void {name}_run_records(const void *in, void *out, size_t n);
void {name}_run_sequence({name}_state_t *state, const {name}_input_t *in, {name}_output_t *out, size_t n);
"""


def controller_harness(name: str) -> str:
    """Batch loops over the flight step; the arithmetic stays in the flight object."""
    return f"""
#include <stddef.h>
#include "{name}.h"
typedef struct {{ {name}_state_t state; {name}_input_t input; }} rec_in_t;
typedef struct {{ {name}_output_t output; {name}_state_t state; }} rec_out_t;
static void {name}_run_records(const void *in, void *out, size_t n)
{{
    const rec_in_t *a = (const rec_in_t *)in;
    rec_out_t *b = (rec_out_t *)out;
    size_t r;
    for (r = 0; r < n; ++r) {{
        b[r].state = a[r].state;
        {name}_step(&b[r].state, &a[r].input, &b[r].output);
    }}
}}
static void {name}_run_sequence({name}_state_t *state, const {name}_input_t *in, {name}_output_t *out, size_t n)
{{
    size_t r;
    for (r = 0; r < n; ++r) {{
        {name}_step(state, in + r, out + r);
    }}
}}
"""


class X86Controller:
    """The generated controller on x86, on numpy structured arrays."""

    def __init__(self, artifact: Artifact, cfg: cs.ControllerConfig, name: str = DEFAULT_NAME):
        sources = controller_sources(artifact, cfg, name)
        self.build = x86.build(sources, controller_cdef(name), controller_harness(name))
        self.name = name
        self.ffi, self.lib = self.build.ffi, self.build.lib
        self.state = self.ffi.new(f"{name}_state_t *")
        self.reset()

    def _ptr(self, arr: np.ndarray, ctype: str):
        return self.ffi.cast(ctype, self.ffi.from_buffer(arr))

    def reset(self) -> None:
        getattr(self.lib, f"{self.name}_init")(self.state)

    def state_array(self) -> np.ndarray:
        return np.frombuffer(self.ffi.buffer(self.state), dtype=STATE_DTYPE).copy()

    def run_records(self, states: np.ndarray, inputs: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Independent steps: (outputs, states after) for each (state, input) row."""
        rec = np.zeros(inputs.shape, dtype=RECORD_IN_DTYPE)
        rec["state"], rec["input"] = states, inputs
        out = np.zeros(inputs.shape, dtype=RECORD_OUT_DTYPE)
        self.build.check_fp_environment()
        getattr(self.lib, f"{self.name}_run_records")(self._ptr(rec, "void *"), self._ptr(out, "void *"), rec.size)
        return out["output"].copy(), out["state"].copy()

    def run_sequence(self, inputs: np.ndarray) -> np.ndarray:
        """Rows as consecutive steps from the current state (carried on)."""
        inputs = np.ascontiguousarray(inputs, dtype=INPUT_DTYPE)
        out = np.zeros(inputs.shape, dtype=OUTPUT_DTYPE)
        self.build.check_fp_environment()
        getattr(self.lib, f"{self.name}_run_sequence")(
            self.state, self._ptr(inputs, f"{self.name}_input_t *"), self._ptr(out, f"{self.name}_output_t *"),
            inputs.size)
        return out
