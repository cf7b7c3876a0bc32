"""The static worst-case bound (tools/m4/wcet.py): exact on the hand-derived micro-benchmarks,
never below what the profiler measures on hostile input, and loud where it cannot bound."""
import numpy as np
import pytest

from codegen.units import kinds
from firmware.arm import BENCH, bench_build
from tests.codegen.units import unit_checks as checks
from tools.cycles import bench_expectations, profile_entry, run_bench
from tools.errors import ToolError
from tools.m4.census import census
from tools.m4.elf import Image
from tools.m4.wcet import Analysis
from tools.report import cycle_report
from tools.runners import arm_build, pack

EXPECT = bench_expectations(BENCH)
TABLES = ("strict", "lenient")


@pytest.fixture(scope="module")
def bench(tmp_path_factory):
    image = Image(bench_build(tmp_path_factory.mktemp("bench")))
    return image, Analysis(image, BENCH)


# Branch-deterministic benchmarks: one path, so the bound is the hand-derived count itself.
DETERMINISTIC = sorted(set(EXPECT) - {"bench_it_blocks", "bench_tbb", "bench_ldr_pc"})


@pytest.mark.parametrize("name", DETERMINISTIC)
@pytest.mark.parametrize("table", TABLES)
def test_bound_is_the_hand_derived_count_on_one_path(bench, name, table):
    _image, an = bench
    assert an.bound(name).cycles[(table, "ideal")] == EXPECT[name][table]


def test_it_skipped_instructions_are_charged_as_executed(bench):
    # bench_it_blocks skips its two LDRNE (1 cycle each when skipped, 2 when executed) and its
    # first BXEQ; the bound takes both loads as executed: the hand count + 2 x (2 - 1).
    _image, an = bench
    for table in TABLES:
        assert an.bound("bench_it_blocks").cycles[(table, "ideal")] == EXPECT["bench_it_blocks"][table] + 2


def test_loop_bound_comes_from_the_source_annotation(bench):
    _image, an = bench
    (header, source, runs), = an.bound("bench_branches").loops
    assert source.startswith("branches.S:") and runs == 4  # do-while: exits from its latch


@pytest.mark.parametrize("name", sorted(set(EXPECT) - {"bench_tbb", "bench_ldr_pc"}))  # no bound: below
def test_art_bound_covers_the_profiled_art_count(bench, name):
    image, an = bench
    run, = run_bench(image, name)
    for table in TABLES:
        assert an.bound(name).cycles[(table, "art")] >= run[table][1]


@pytest.mark.parametrize("name, what", [("bench_tbb", "tbb"), ("bench_ldr_pc", "ldr.w pc")])
def test_indirect_jumps_have_no_bound(bench, name, what):
    _image, an = bench
    with pytest.raises(ToolError, match=f"indirect jump .*{what}.*no static bound") as err:
        an.bound(name)
    assert "\n" not in str(err.value)


def test_a_loop_without_annotation_is_an_error(tmp_path):
    unit = checks.example_unit(kinds()["network"])
    build = arm_build(unit)
    with pytest.raises(ToolError, match="has no `wcet: loop bound N` annotation"):
        Analysis(Image(build.elf), tmp_path).bound(unit.step_symbol)  # no sources: no annotations


# ----------------------------------------------------------------- soundness on hostile input

RANDOM_RECORDS = 10_000


@pytest.mark.parametrize("kind", ["network", "controller", "tanh", "rbf", "gp"])
def test_bound_covers_every_sampled_count_on_random_bits(kind):
    """>= 10,000 records of random bits (NaN, Inf, subnormal, huge, random state) under the profiler:
    no evaluation may exceed the static bound, in either table or memory mode."""
    unit = checks.example_unit(kinds()[kind])
    build = arm_build(unit)
    image = Image(build.elf)
    n_in = image.word("adapter_in_bytes")
    records = np.random.default_rng(16).integers(0, 256, (RANDOM_RECORDS, n_in), dtype=np.uint8)
    prof = profile_entry(image, unit.step_symbol, {"random": records}, ("ideal", "art"), unit.max_instructions)
    fb = Analysis(image, build.elf.parent / "src").bound(unit.step_symbol)
    assert prof.evaluations == RANDOM_RECORDS
    for table, sampled in (("strict", prof.cycles), ("lenient", prof.cycles_lenient)):
        for mode in ("ideal", "art"):
            assert sampled[mode]["max"] <= fb.cycles[(table, mode)], (table, mode)


# ----------------------------------------------------------------- tightness (SPEC 8 uses both)

@pytest.mark.parametrize("kind", ["network", "controller", "rbf", "gp"])
def test_bound_is_within_15_percent_of_the_sampled_max(kind):
    """The network path and the whole step: the static bound is at most 15 % above the largest
    count over the unit's own cycle classes (ideal, strict), so the bound is a figure to sign,
    not a loose ceiling."""
    unit = checks.example_unit(kinds()[kind])
    rep = cycle_report(unit, ("ideal",), per_class=100, seed=0)
    assert rep["bound"]["strict"]["ideal"] <= 1.15 * rep["cycles"]["ideal"]["max"], rep["bound"]


def test_network_hot_path_has_no_strict_stalls():
    """The census of one evaluation (tools/m4/census.py): the generated path leaves the strict
    table's FP result-use, address-generation and branch-alignment stalls out of its code (the
    earlier build had 360, 41 and 21), and every event is counted on the traced instructions."""
    unit = checks.example_unit(kinds()["network"])
    build = arm_build(unit)
    batch = unit.cycle_classes(3, 0)["inside"]
    record = pack(unit, batch).view(np.uint8).reshape(batch.input.shape[0], -1)[0]
    n = census(build.elf, build.elf.parent / "src", unit.step_symbol, record)
    assert n["instructions"] > 2_000 and n["VMOV core<->S"] >= 40   # one VMOV per hidden neuron at least
    assert n["FP result read by the next instruction"] == 0
    assert n["address written by the instruction just before"] == 0
    assert n["taken to a 32-bit halfword target"] == 0


# ------------------------------------------------------------------ art: code beyond the cache

BIG_STRAIGHT_LINE = """
  .syntax unified
  .thumb
  .text
  .global big
  .type big, %function
  .p2align 4
big:
  .rept 140
  cmp r0, r0
  bne.w 1f            @ never taken: each ends a block in the middle of a flash line
  add.w r1, r1, #1
  .endr
1:
  bx lr
  .size big, . - big
"""


def test_art_bound_charges_a_line_shared_by_two_blocks_once(tmp_path):
    # 1,402 bytes of straight-line code: more than the ART's 64 lines, so the bound charges
    # block by block. Every line is fetched once (5 wait states); a block starting in the line the
    # previous one ends in reads the ART's current line and must not be charged again.
    src = tmp_path / "big.S"
    src.write_text(BIG_STRAIGHT_LINE)
    image = Image(bench_build(tmp_path, [src]))
    fn = image.function("big")
    lines = (fn.start + fn.size - 1) // 16 - fn.start // 16 + 1
    assert lines > 64
    bound = Analysis(image, tmp_path).bound("big")
    run, = run_bench(image, "big")
    for table in TABLES:
        assert bound.cycles[(table, "art")] - bound.cycles[(table, "ideal")] == 5 * lines
        assert run[table][1] - run[table][0] == 5 * lines
        assert bound.cycles[(table, "art")] >= run[table][1]
