"""The math library's own coverage run: every branch of sg_math.c / sg_math.h taken, every result
equal to the numpy twin; a planted unreachable branch and a changed coefficient are both seen."""
from __future__ import annotations

from codegen.cgen import math_sources
from tools.coverage_library import OPS, library_lines, measure_library, vectors


def test_every_library_branch_is_taken_and_every_result_matches_the_twin():
    lib = measure_library(n=1_000, seed=3)
    taken, total = lib.report.branches
    assert total > 100 and taken == total, library_lines(lib)
    assert lib.report.unused == []
    assert set(lib.mismatches) == {op.name for op in OPS} | {"sg_crc32"}
    assert all(v == 0 for v in lib.mismatches.values()), lib.mismatches


def test_a_planted_branch_and_a_changed_coefficient_are_reported():
    src = math_sources()
    c = src["sg_math.c"]
    anchor = "float sg_sqrtf(float x)\n{\n"
    assert anchor in c
    c = c.replace(anchor, anchor + "    if (x == 0x1.23456p+100f) {   /* PLANTED */\n        x = 1.0f;\n    }\n", 1)
    assert c.count("0x1.5554b6p-3f") == 1                           # a coefficient of sg_expm1_kernel
    c = c.replace("0x1.5554b6p-3f", "0x1.5554b8p-3f")
    lib = measure_library(n=500, seed=4, sources={**src, "sg_math.c": c})
    lines = c.splitlines()
    untaken = [ln for ln, _ in lib.report.files["sg_math.c"].untaken]
    assert untaken and all("PLANTED" in lines[ln - 1] for ln in untaken)
    assert lib.mismatches["sg_expf"] > 0 and lib.mismatches["sg_sqrtf"] == 0


def test_vectors_hold_the_specials_and_both_argument_orders():
    v = vectors(50, seed=0)
    a, b = v["sg_atan2f"]
    pairs = set(zip(a.tolist(), b.tolist()))
    assert (0x7FC00000, 0x7F800000) in pairs and (0x7F800000, 0x7FC00000) in pairs
    assert 0x80000000 in set(v["sg_asinf"][0].tolist())
