"""The Cortex-M4 cycle model against hand-derived counts, and its failure modes.

Every micro-benchmark in firmware/bench/*.S carries its expected counts under both timing tables,
derived by hand from the TRM in the comment beside it (line by line, "lenient | strict"); the
model must reproduce each exactly in `ideal` mode.
"""
import capstone
import numpy as np
import pytest
from unicorn.arm_const import UC_ARM_REG_R0

from codegen.units import kinds
from tests.codegen.units import unit_checks as checks
from tools.m4.harness import Harness
from tools.runners import arm_build, pack

from firmware.arm import BENCH, bench_build
from tools import stack
from tools.cycles import SCRATCH, bench_expectations, run_bench
from tools.errors import ToolError
from tools.m4.elf import Image
from tools.m4.machine import Machine
from tools.m4.profile import Profiler
from tools.m4.timing import P, cost_of

EXPECT = bench_expectations(BENCH)


@pytest.fixture(scope="module")
def bench(tmp_path_factory) -> Image:
    return Image(bench_build(tmp_path_factory.mktemp("bench")))


def test_every_benchmark_has_an_expectation():
    # The groups the issue asks for: ALU, dependent/independent loads, LDM/VLDM, branches,
    # IT blocks, VDIV/VMLA, a PC-writing POP.
    for name in ("bench_alu_chain", "bench_loads_dependent", "bench_loads_independent",
                 "bench_ldm_stm", "bench_vldm_vstm", "bench_branches", "bench_it_blocks",
                 "bench_fpu", "bench_pop_pc", "bench_tbb", "bench_fp_loads",
                 # one per rule of the strict table
                 "bench_fp_result_use", "bench_agu", "bench_branch_align", "bench_literal",
                 "bench_ldr_pc", "bench_vmov", "bench_store"):
        assert name in EXPECT


@pytest.mark.parametrize("name", sorted(EXPECT))
@pytest.mark.parametrize("table", ["strict", "lenient"])
def test_benchmark_exact_in_ideal_mode(bench, name, table):
    run, = run_bench(bench, name)
    assert run[table][0] == EXPECT[name][table]


def test_a_flash_read_inside_an_it_block_leaves_no_stale_it_state(bench):
    """Unicorn 2.1 restores the IT bits at a memory hook inside an IT block and leaves them set: the
    next translation block then skips its first instruction when the IT condition has changed
    (bench_it_flash_read returns 0 instead of 1). The flash models' read hook clears them."""
    for memory_modes in (False, True):
        prof = Profiler(bench, "bench_it_flash_read", memory_modes=memory_modes)
        prof.run("bench_it_flash_read", (SCRATCH,))
        assert prof.machine.uc.reg_read(UC_ARM_REG_R0) == 1, memory_modes


def test_every_strict_rule_changes_its_benchmark():
    # Each rule's benchmark differs between the tables, so a rule that stopped firing fails.
    for name in ("bench_fp_result_use", "bench_agu", "bench_branch_align", "bench_literal",
                 "bench_ldr_pc", "bench_vmov", "bench_store", "bench_fpu", "bench_tbb"):
        assert EXPECT[name]["strict"] != EXPECT[name]["lenient"]


# Flash-line counts below follow from each function starting on a 16-byte line (.p2align 4)
# and its byte length; a miss or a new line costs 5 wait states.
@pytest.mark.parametrize("name, art, pess", [
    # 26 bytes = 2 lines, each missed once; the loop re-runs inside line 0 (hit, same line).
    ("bench_branches", 34 + 2 * 5, 34 + 2 * 5),
    # caller (line A) and sub (line B): ART misses A, B once; without ART the return to A
    # needs line A again: A, B, A.
    ("bench_pop_pc", 21 + 2 * 5, 21 + 3 * 5),
    # 12 bytes = 1 line, plus TBB's table byte read from flash (one D-cache miss / one read).
    ("bench_tbb", 8 + 5 + 5, 8 + 5 + 5),
])
def test_memory_modes_hand_derived(bench, name, art, pess):
    run, = run_bench(bench, name)
    assert run["lenient"] == (EXPECT[name]["lenient"], art, pess)
    # The memory stalls are the same events under both tables.
    d = EXPECT[name]["strict"] - EXPECT[name]["lenient"]
    assert run["strict"] == (EXPECT[name]["strict"], art + d, pess + d)


def test_call_stack_tracker_inclusive_and_exclusive(bench):
    prof = Profiler(bench, "bench_pop_pc")
    prof.machine.write(SCRATCH, bytes(256))
    prof.run("bench_pop_pc", (SCRATCH,))
    ev, = prof.evaluations
    names = {bench.functions[fid].name: fid for fid in ev.calls}
    sub, top = names["bench_pop_pc_sub"], names["bench_pop_pc"]
    assert ev.incl[sub][0] == ev.excl[sub][0] == 3 + 1 + (1 + 2 + P)
    assert ev.incl[top][0] == 21 and ev.excl[top][0] == 21 - 9
    assert ev.calls[sub] == 1


def _decode(code: bytes):
    cs = capstone.Cs(capstone.CS_ARCH_ARM, capstone.CS_MODE_THUMB | capstone.CS_MODE_MCLASS)
    cs.detail = True
    return next(cs.disasm(code, 0x08000000))


@pytest.mark.parametrize("code, cycles", [
    (bytes.fromhex("f1ee10fa"), 1),    # vmrs APSR_nzcv, fpscr (Capstone id FMSTAT)
    (bytes.fromhex("b7ee000a"), 1),    # vmov.f32 s0, #1.0 (Capstone id FCONSTS)
    (bytes.fromhex("00ee100a"), 2),    # vmov s0, r0
    (bytes.fromhex("80ee010a"), 14),   # vdiv.f32 s0, s0, s2
    (bytes.fromhex("00ee010a"), 3),    # vmla.f32 s0, s0, s2
    (bytes.fromhex("bde8f087"), 1 + 8 + P),  # pop.w {r4-r10, pc}
    (bytes.fromhex("5df804fb"), 2 + P),      # ldr pc, [sp], #4
    (bytes.fromhex("90fbf1f0"), 12),         # sdiv r0, r0, r1 (worst case of 2..12)
])
def test_timing_table_entries(code, cycles):
    assert cost_of(_decode(code)).cycles == cycles


def test_stack_bound_from_prologues(bench):
    # No .su for assembly: frames come from the prologues (push {r4, lr} = 8 B each).
    bound = stack.worst_case(bench, [], "bench_pop_pc")
    assert bound.bytes == 16 and bound.path == ["bench_pop_pc", "bench_pop_pc_sub"]


# ----------------------------------------------------------------------------- failure modes

def test_corrupt_elf_is_one_line_error(tmp_path):
    bad = tmp_path / "bad.elf"
    bad.write_bytes(b"\x7fELF" + bytes(60))
    with pytest.raises(ToolError, match="corrupt ELF|not an ARM ELF") as err:
        Image(bad)
    assert "\n" not in str(err.value)
    (tmp_path / "text.elf").write_text("not an elf at all")
    with pytest.raises(ToolError, match="corrupt ELF"):
        Image(tmp_path / "text.elf")


def test_missing_symbol(bench):
    with pytest.raises(ToolError, match="symbol 'network_eval' is not in"):
        Machine(bench).call("network_eval")


def test_runaway_loop_is_capped(bench):
    m = Machine(bench)
    m.write(SCRATCH, bytes.fromhex("fee7"))  # b .
    with pytest.raises(ToolError, match="did not return within 100000 instructions"):
        m.call(SCRATCH, max_insns=100_000)


def test_runaway_loop_is_capped_under_the_profiler(bench):
    prof = Profiler(bench, "bench_alu_chain")
    prof.machine.write(SCRATCH, bytes.fromhex("fee7"))
    with pytest.raises(ToolError, match="did not return"):
        prof.run(SCRATCH, max_insns=50_000)


def test_invalid_memory_access(bench):
    # A dependent load chain starting from an unmapped peripheral address.
    with pytest.raises(ToolError, match="invalid memory access .* at 0x40000000"):
        Machine(bench).call("bench_loads_dependent", (0x40000000,))


def test_breakpoint_stops_with_error(bench):
    m = Machine(bench)
    m.write(SCRATCH, bytes.fromhex("00be"))  # bkpt #0, as in Default_Handler
    with pytest.raises(ToolError, match="exception"):
        m.call(SCRATCH)


# --------------------------------------------------------------- profiling does not change execution

@pytest.mark.parametrize("kind", ["network", "controller", "tanh"])
def test_profiling_leaves_the_execution_unchanged(kind):
    """The profiler's hooks must not alter what the emulator computes: a code or memory hook on an
    instruction inside an IT block corrupts Unicorn's IT state (later instructions skipped; found
    here on the controller's random-bit records). Outputs with and without the profiler, bit for
    bit, over the unit's cycle classes and random bits."""
    unit = checks.example_unit(kinds()[kind])
    image = Image(arm_build(unit).elf)
    parts = [pack(unit, b).view(np.uint8).reshape(b.input.shape[0], -1) for b in unit.cycle_classes(40, 3).values()]
    parts.append(np.random.default_rng(5).integers(0, 256, (300, image.word("adapter_in_bytes")), dtype=np.uint8))
    records = np.vstack(parts)
    prof = Profiler(image, unit.step_symbol)
    profiled = Harness(image, machine=prof.machine)
    profiled.reset(runner=prof.run)
    got = profiled.run(records, runner=prof.run)
    assert np.array_equal(got, Harness(image).run(records))
    assert len(prof.evaluations) == records.shape[0]
