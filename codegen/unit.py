"""The generated-unit interface: what every unit of flight C tells the rest of the tool chain.

A unit is one generated entry point with its golden model (the network path, the Fig. 2
controller, the tanh law, ...). It lives in one folder, `codegen/units/<unit>/` (emitter, golden
model, spec or parameters, templates, gate vectors), whose `__init__.py` defines `KIND`, a
`UnitKind`: that is its one registration (`codegen.units.kinds()` finds it). Everything
downstream — the x86 loader, the ARM adapters, the bit-exact gate, the cycle / size / stack
report, the in-the-loop runner (all in `tools/`) — is written once against this interface.

The numbers a unit exchanges with its C are numpy structured arrays whose dtypes equal the C
structs: every field a 4-byte scalar or an array of them (float32, uint32, int32), so there is
no padding and the numpy offsets are the C offsets (the x86 loader checks sizeof and offsetof of
every field against the compiled C). A stateless unit (the network path) has `state is None`.

Step contract, the same for the golden model and the C:
    stateful    out, state_after = golden(state_before, inp)      C: <entry>_step(&state, &in, &out)
    stateless   out, None        = golden(None, inp)              C: <step_symbol>(in, out)
"""
from __future__ import annotations

from abc import ABC, abstractmethod
from dataclasses import dataclass
from typing import Callable, NamedTuple

import numpy as np

from codegen.errors import CodegenError

# Field base types a unit may exchange with its C (4 bytes each: no padding anywhere).
WORD_TYPES = (np.dtype("<f4"), np.dtype("<u4"), np.dtype("<i4"))


class Batch(NamedTuple):
    """N independent steps: the state before each (None for a stateless unit) and the input."""

    state: np.ndarray | None
    input: np.ndarray


@dataclass(frozen=True)
class Budgets:
    """SPEC section 8 budgets of one unit (None: no budget stated for that figure)."""

    cycles: int | None = None     # worst case of the step, ideal memory (strict table, static bound)
    cycles_art: int | None = None  # the same with flash wait states and the ART accelerator
    flash: int | None = None      # bytes of the unit's objects (code + constants)
    ram: int | None = None        # static RAM + the caller-owned state
    stack: int | None = None      # worst-case stack of the step


@dataclass(frozen=True)
class FieldDoc:
    """One record field as the interface control document states it (the package's ICD.md)."""

    name: str          # the C struct member (the dtype field)
    unit: str          # physical unit, e.g. "rad/s", "N*m", "-" for dimensionless, "bits" for a status word
    frame: str         # frame of the components, e.g. "S_b", "ECI", "-" when not a vector
    range: str         # accepted / produced range and what happens outside it
    meaning: str       # one sentence


@dataclass(frozen=True)
class StatusBit:
    """One bit (or field) of a unit's status word, for the ICD."""

    name: str          # the C macro, without the entry prefix, e.g. "STATUS_PID"
    mask: int
    meaning: str


@dataclass(frozen=True)
class Stage:
    """A stateless sub-function of a unit, exposed for stage-by-stage tests (e.g. normalise)."""

    symbol: str
    input: np.dtype
    output: np.dtype
    golden: Callable[[np.ndarray], np.ndarray]   # input records -> output records
    c_input: str                                 # C type of its input (see Unit.c_types)
    c_output: str


def check_dtype(dtype: np.dtype, what: str) -> np.dtype:
    """A record dtype the C can share: structured, every field a 4-byte word or an array of them."""
    if dtype.names is None:
        raise CodegenError(f"{what}: must be a structured dtype")
    offset = 0
    for name in dtype.names:
        sub, off = dtype.fields[name][:2]
        if sub.base not in WORD_TYPES or off != offset:
            raise CodegenError(f"{what}.{name}: fields must be packed 4-byte float32/uint32/int32 words")
        offset += sub.itemsize
    if offset != dtype.itemsize:
        raise CodegenError(f"{what}: itemsize {dtype.itemsize} is not the sum of its fields ({offset})")
    return dtype


def class_sizes(n: int, classes: tuple[str, ...], kind: str) -> list[int]:
    """n gate vectors split evenly over the classes (the first takes the remainder); at least one each."""
    if n < len(classes):
        raise CodegenError(f"unit {kind}: need at least {len(classes)} vectors (one per class), got {n}")
    sizes = [n // len(classes)] * len(classes)
    sizes[0] += n - sum(sizes)
    return sizes


def records(dtype: np.dtype, n: int) -> np.ndarray:
    """n zeroed records of a unit dtype."""
    return np.zeros(n, dtype=dtype)


def words(a: np.ndarray) -> np.ndarray:
    """A record array as its raw 32-bit words, (N, itemsize / 4) uint32 (bit-exact comparisons)."""
    a = np.ascontiguousarray(a)
    return a.view(np.uint32).reshape(a.shape[0], -1)


class Unit(ABC):
    """One generated unit bound to its inputs (artifact, parameters, configuration)."""

    kind: str = ""                 # registry name, e.g. "network"
    # Emulator cap per step (a runaway loop ends in an error, not a hang); the network needs a few
    # thousand instructions, a unit that scans tables (dp) sets its own.
    max_instructions: int = 1_000_000
    # Where the constant tables run on the STM32F417: "ccm" (64 KB of zero-wait-state data RAM,
    # copied from flash at start-up) or "flash" (tables larger than CCM; every load may wait).
    tables_in: str = "ccm"

    def __init__(self, entry: str, input_dtype: np.dtype, output_dtype: np.dtype,
                 state_dtype: np.dtype | None, budgets: Budgets):
        self.entry = entry
        self.input_dtype = check_dtype(np.dtype(input_dtype), f"{self.kind} input")
        self.output_dtype = check_dtype(np.dtype(output_dtype), f"{self.kind} output")
        self.state_dtype = None if state_dtype is None else check_dtype(np.dtype(state_dtype), f"{self.kind} state")
        self.budgets = budgets

    # ------------------------------------------------------------------ what the C is
    @property
    def stateful(self) -> bool:
        return self.state_dtype is not None

    @property
    def header(self) -> str:
        return f"{self.entry}.h"

    @property
    def step_symbol(self) -> str:
        """The C function of one step (the cycle model's entry)."""
        return f"{self.entry}_step"

    @property
    def init_symbol(self) -> str | None:
        return f"{self.entry}_init" if self.stateful else None

    @property
    def integrity_symbol(self) -> str | None:
        """`uint32_t f(state *)` that checks the unit's constant tables (0: intact), if it has one."""
        return None

    @property
    def c_types(self) -> dict[str, str]:
        """C type of each record ("input", "output", and "state" if stateful): a struct name
        (sizeof and offsetof of every field are checked) or an array type like float[N_IN]."""
        types = {"input": f"{self.entry}_input_t", "output": f"{self.entry}_output_t"}
        if self.stateful:
            types["state"] = f"{self.entry}_state_t"
        return types

    @property
    def objects(self) -> tuple[str, ...]:
        """Object files whose bytes are the unit's flash and RAM (after --gc-sections)."""
        return tuple(f[:-2] + ".o" for f in sorted(self.sources()) if f.endswith(".c"))

    @property
    def stages(self) -> dict[str, Stage]:
        """Stateless sub-functions exposed to the stage tests (default: none)."""
        return {}

    def identity(self) -> str:
        """One line naming the unit and what it was generated from (reports, logs)."""
        return f"{self.kind} ({self.entry})"

    @abstractmethod
    def sources(self) -> dict[str, str]:
        """{file name: text} of every C file the unit needs (its math library included)."""

    # ------------------------------------------------------------------ the golden model
    @abstractmethod
    def golden(self, state: np.ndarray | None, inp: np.ndarray) -> tuple[np.ndarray, np.ndarray | None]:
        """One step for each row: (outputs, states after) — the C's operations, bit for bit."""

    def init_state(self, n: int) -> np.ndarray | None:
        """n states as `<entry>_init` leaves them (zeros unless a unit says otherwise)."""
        return records(self.state_dtype, n) if self.stateful else None

    def golden_sequences(self, inputs: np.ndarray) -> np.ndarray:
        """S independent time series from init: inputs (S, T) -> outputs (S, T)."""
        n_seq, steps = inputs.shape
        state = self.init_state(n_seq)
        out = np.zeros((n_seq, steps), dtype=self.output_dtype)
        for t in range(steps):
            out[:, t], state = self.golden(state, np.ascontiguousarray(inputs[:, t]))
        return out

    # ------------------------------------------------------------------ verification inputs
    @abstractmethod
    def gate_classes(self, n: int, seed: int) -> dict[str, Batch]:
        """n independent steps in named classes (deterministic in seed): inside the envelope, on
        its edges, outside it, special values, and whatever the unit adds."""

    def gate_sequences(self, n_seq: int, steps: int, seed: int) -> np.ndarray | None:
        """(n_seq, steps) inputs flown from init with the state carried inside the C (stateful
        units), or None."""
        return None

    def cycle_classes(self, per_class: int, seed: int) -> dict[str, Batch]:
        """The cycle report's input classes, per_class rows each (default: the gate classes)."""
        classes = self.gate_classes(per_class * 8, seed)
        return {c: Batch(None if b.state is None else b.state[:per_class], b.input[:per_class])
                for c, b in classes.items()}

    def check_outputs(self, out: np.ndarray) -> list[str]:
        """Invariants of the golden outputs beyond bit-exactness (e.g. a torque bound); [] if held."""
        return []

    def check_state(self, state: np.ndarray) -> list[str]:
        """Invariants of the golden states after a step (stateful units, e.g. weights within their
        bounds); [] if held. The gate and the fuzzer apply it to every state they compute."""
        return []

    def describe_outputs(self, out: np.ndarray) -> str | None:
        """One line summarising golden outputs (e.g. status counts), or None."""
        return None

    def extra_report(self, batches: dict[str, Batch], outputs: dict[str, np.ndarray]) -> list[str]:
        """Unit-specific lines for the gate report (e.g. the network's float64 reference error)."""
        return []

    def extra_cycle_facts(self, profile_functions: dict, by_class: dict) -> dict:
        """Unit-specific figures for the cycle report (e.g. the controller without its network)."""
        return {}

    def values_sha256(self) -> str | None:
        """sha256 of the values the C bakes in from the unit's parameter file (with the control
        period), recorded in a package's manifest; None for units without one."""
        return None

    # ------------------------------------------------------------------ interface documentation
    def field_docs(self) -> dict[str, list[FieldDoc]]:
        """{"input": [...], "output": [...], "state": [...]}: every dtype field with unit, frame and
        range, for the flight package's ICD (default: nothing documented; the ICD then lists the
        fields with their types only and says so)."""
        return {}

    def status_bits(self) -> list[StatusBit]:
        """The status word's bits, for the ICD (default: none)."""
        return []


@dataclass(frozen=True)
class UnitKind:
    """A unit's registration: its name, a line of help, and how to bind it to its inputs.

    `configure(**inputs)` receives the keyword inputs the CLI or a caller has (artifact=,
    params=, period=, config=, scenario=, name=), takes those it needs and refuses a missing one
    with a CodegenError. `example()` gives small inputs for the tests written once for every
    unit (tests/codegen/units/test_every_unit.py): registering a unit is what gets it tested.
    `load_params(path)` reads and validates the unit's own parameter file (units that need
    `params`); its errors are one-line CodegenErrors. `takes_period`: the unit bakes a control
    period into its C (`--period`, a package's period); False for a law that has none (gp)."""

    name: str
    summary: str
    needs: tuple[str, ...]
    configure: Callable[..., Unit]
    example: Callable[[], dict]
    load_params: Callable[[object], object] | None = None
    takes_period: bool = True
