"""What every generated unit must do, written once (used by test_every_unit.py over the registered
units and by tests/tools/test_new_unit.py for a unit registered from a folder of its own)."""
from __future__ import annotations

import ast
import copy
import importlib
import re
import subprocess
from pathlib import Path

import numpy as np
import pytest

from codegen import GENERATOR_VERSION
from codegen.unit import Batch, Unit
from firmware import arm, symbols
from firmware.errors import FirmwareError
from host.sim.scenarios import configure_unit
from tools.gate import compare_fields, run_gate
from tools.runners import X86Runner, arm_build, runner

HEX_LITERAL = re.compile(r"(-?0x[0-9a-f]\.[0-9a-f]+p[+-]\d+)f")
BANNED_NUMPY = {"tanh", "exp", "log", "sin", "cos", "sqrt", "power", "dot", "sum", "matmul", "einsum", "cumsum",
                "prod", "inner", "tensordot", "arctan2", "arcsin"}


def example_unit(kind) -> Unit:
    """The kind bound to its example inputs plus what the host adds (configuration, scenarios)."""
    return configure_unit(kind.name, **kind.example())


def step_file(unit: Unit) -> str:
    """The unit's own .c file holding its step (not the shared math library)."""
    return f"{unit.entry}.c"


def check_gate_passes(unit: Unit, n: int = 2_000, n_seq: int = 2, steps: int = 200) -> None:
    lines: list[str] = []
    result = run_gate(unit, n, n_seq, steps, seed=3, targets=("x86", "arm"), log=lines.append)
    assert result.ok, "\n".join(lines)
    assert sum(result.counts.values()) == n and len(result.counts) >= 3
    assert result.sequences == (n_seq if unit.stateful else 0)


def nudged(unit: Unit, which: int = 0) -> Unit:
    """The same unit whose step file has its `which`-th hex-float constant moved by one ulp."""
    sources = unit.sources()
    text = sources[step_file(unit)]
    m = list(HEX_LITERAL.finditer(text))[which]
    value = np.float32(float.fromhex(m.group(1)))
    bumped = np.nextafter(value, np.float32(np.inf))
    sources[step_file(unit)] = text[:m.start(1)] + float(bumped).hex() + text[m.end(1):]
    other = copy.copy(unit)
    other.sources = lambda: dict(sources)
    return other


def check_one_ulp_change_is_caught(unit: Unit) -> None:
    """A C whose first constant differs by one ulp does not pass the gate on x86."""
    classes = unit.gate_classes(2_000, seed=5)
    run = runner(nudged(unit), "x86")
    problems = []
    for b in classes.values():
        g_out, g_state = unit.golden(b.state, b.input)
        out, state = run.records(b)
        problems += compare_fields(g_out, out) + (compare_fields(g_state, state) if unit.stateful else [])
    assert problems, "a one-ulp change of a constant went through the gate"


def check_golden_refuses_float64(unit: Unit) -> None:
    b = next(iter(unit.gate_classes(64, seed=0).values()))

    def widened(dtype):
        return np.dtype([(n, "<f8" if dtype[n].base == np.float32 else dtype[n].base, dtype[n].shape)
                         for n in dtype.names])
    inp64 = b.input.astype(widened(unit.input_dtype))
    with pytest.raises(ValueError):
        unit.golden(b.state, inp64)


def check_golden_follows_spec_6(unit: Unit) -> None:
    """No numpy library math, no reordering sums, no @ or ** in the unit's golden module."""
    module = importlib.import_module(type(unit).__module__.rsplit(".", 1)[0] + ".golden")
    tree = ast.parse(Path(module.__file__).read_text())
    used = {n.attr for n in ast.walk(tree) if isinstance(n, ast.Attribute) and isinstance(n.value, ast.Name)
            and n.value.id == "np"}
    assert not used & BANNED_NUMPY, used & BANNED_NUMPY
    assert not any(isinstance(n, ast.BinOp) and isinstance(n.op, ast.MatMult) for n in ast.walk(tree))
    # a power only between Python constants (2.0**-10 is an exact constant, not an array operation)
    assert all(_constant(n.left) and _constant(n.right) for n in ast.walk(tree)
               if isinstance(n, ast.BinOp) and isinstance(n.op, ast.Pow))
    assert not any(isinstance(n, ast.Name) and n.id == "sum" for n in ast.walk(tree))


def _constant(node) -> bool:
    return isinstance(node, ast.Constant) or (isinstance(node, ast.UnaryOp) and isinstance(node.operand, ast.Constant))


def check_no_libm_no_malloc(unit: Unit) -> None:
    """Neither build references libm or an allocator (x86 objects, ARM image)."""
    build = X86Runner(unit).build
    res = subprocess.run(["nm", "--undefined-only", *map(str, build.objects)], capture_output=True, text=True)
    names = {ln.split()[-1] for ln in res.stdout.splitlines() if ln.strip() and not ln.endswith(":")}
    assert not {n for n in names if symbols.LIBM.match(n) or symbols.ALLOCATION.match(n)}, names
    elf = arm_build(unit).elf
    arm.check_symbols(elf)
    defined = subprocess.run([arm.tool(arm.ARM_NM), str(elf)], capture_output=True, text=True).stdout
    assert not re.search(r"\b(malloc|calloc|realloc|free|_sbrk)\b", defined)


def check_regeneration_is_byte_identical(kind) -> None:
    a, b = example_unit(kind).sources(), example_unit(kind).sources()
    assert a == b and a
    assert any(GENERATOR_VERSION in text for name, text in a.items() if name.endswith(".h"))


def check_a_drifted_dtype_is_refused(unit: Unit) -> None:
    """The record dtypes are checked against the C structs: one extra input field fails the build."""
    other = copy.copy(unit)
    fields = [(n, unit.input_dtype[n].base.str, unit.input_dtype[n].shape) for n in unit.input_dtype.names]
    other.input_dtype = np.dtype(fields + [("drift", "<f4")])
    with pytest.raises(FirmwareError, match="does not compile"):
        X86Runner(other)


def check_sequences_carry_the_state(unit: Unit) -> None:
    """Stateful units: sequences from init on x86 and ARM equal the golden model step for step."""
    seqs = unit.gate_sequences(2, 50, seed=2)
    golden = unit.golden_sequences(seqs)
    for target in ("x86", "arm"):
        run = runner(unit, target)
        for s in range(seqs.shape[0]):
            run.reset()
            assert compare_fields(golden[s], run.sequence(seqs[s])) == []


def check_records_are_independent(unit: Unit) -> None:
    """Each record steps from its own state: reversing the rows reverses the outputs (ARM records)."""
    b = next(iter(unit.gate_classes(40, seed=4).values()))
    out, _ = runner(unit, "arm").records(b)
    rev = Batch(None if b.state is None else b.state[::-1].copy(), b.input[::-1].copy())
    out_rev, _ = runner(unit, "arm").records(rev)
    assert compare_fields(out[::-1].copy(), out_rev) == []


CANONICAL_NAN = 0x7FC00000


def check_nan_outputs_are_canonical(unit: Unit) -> int:
    """Every float output word that is a NaN is the canonical 0x7FC00000, in the golden model and in
    the x86 C, over the gate classes (special values included): the gate needs no NaN class.
    Returns how many NaN words it saw."""
    x86 = X86Runner(unit)
    seen = 0
    for batch in unit.gate_classes(4_000, seed=11).values():
        for out in (unit.golden(batch.state, batch.input)[0], x86.records(batch)[0]):
            for name in out.dtype.names:
                values = np.ascontiguousarray(out[name])
                if values.dtype.base != np.float32:
                    continue
                bits = values.view(np.uint32)
                nan = np.isnan(values)
                seen += int(nan.sum())
                assert np.all(bits[nan] == CANONICAL_NAN), (unit.kind, name, hex(int(bits[nan][0])))
    return seen
