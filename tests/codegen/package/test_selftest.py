"""The package self-test C: it passes on the code it was made from, counts planted faults, and its
floating-point environment checks fire for the environments they name (x86-64, gcc)."""
from __future__ import annotations

import re
import subprocess

import numpy as np
import pytest

from codegen.artifact import random_artifact
from codegen.errors import CodegenError
from codegen.package.selftest import field_elements, make_vectors, selftest_sources
from codegen.units.tanh.params import example_params
from firmware.flags import COMMON
from host.sim.scenarios import configure_unit

MAIN = r"""
#include <fenv.h>
#include <stdio.h>
#include <xmmintrin.h>
#include "stare_selftest.h"
int main(int argc, char **argv)
{
    if (argc > 1 && argv[1][0] == 'z') _mm_setcsr(_mm_getcsr() | 0x8040u);   /* FTZ + DAZ */
    if (argc > 1 && argv[1][0] == 'f') _mm_setcsr(_mm_getcsr() | 0x8000u);   /* FTZ alone */
    if (argc > 1 && argv[1][0] == 'a') _mm_setcsr(_mm_getcsr() | 0x0040u);   /* DAZ alone */
    if (argc > 1 && argv[1][0] == 'u') fesetround(FE_UPWARD);
    if (argc > 1 && argv[1][0] == 'd') fesetround(FE_DOWNWARD);
    if (argc > 1 && argv[1][0] == 't') fesetround(FE_TOWARDZERO);
    unsigned env = (unsigned)stare_selftest_fp_environment();
    int r = stare_selftest();
    printf("%d %u\n", r, env);
    return 0;
}
"""


@pytest.fixture(scope="module")
def units():
    c = configure_unit("controller", artifact=random_artifact((12, 40, 3), seed=1), name="stare")
    t = configure_unit("tanh", params=example_params(), name="stare_tanh")
    return c, t


@pytest.fixture(scope="module")
def package_sources(units):
    c, t = units
    vectors = [make_vectors(c, 64, 0), make_vectors(t, 64, 0)]
    return {**c.sources(), **t.sources(), **selftest_sources("stare", vectors)}, vectors


def build(tmp_path, files, flags=(), main=MAIN) -> str:
    for name, text in files.items():
        (tmp_path / name).write_text(text)
    (tmp_path / "main.c").write_text(main)
    exe = tmp_path / "selftest"
    flight = [f for f in COMMON if f != "-Werror"] if flags else COMMON
    srcs = [str(p) for p in sorted(tmp_path.glob("*.c")) if p.name != "main.c"]
    objs = []
    for src in srcs:
        obj = src[:-2] + ".o"
        subprocess.run(["gcc", *flight, *flags, "-c", src, "-o", obj], check=True, capture_output=True)
        objs.append(obj)
    subprocess.run(["gcc", "-O1", "-I", str(tmp_path), str(tmp_path / "main.c"), *objs, "-o", str(exe), "-lm"],
                   check=True, capture_output=True)
    return str(exe)


def run(exe, *args) -> tuple[int, int]:
    out = subprocess.run([exe, *args], check=True, capture_output=True, text=True).stdout.split()
    return int(out[0]), int(out[1])


def test_vectors_cover_every_gate_class(units):
    for unit in units:
        v = make_vectors(unit, 256, 0)
        assert v.n == 256 and sum(v.classes.values()) == 256
        assert set(v.classes) == set(unit.gate_classes(256, 0))
        out, after = unit.golden(v.state.copy(), v.input)     # the expected words are the golden model's
        assert np.array_equal(out.view(np.uint8), v.output.view(np.uint8))


def test_selftest_passes_and_counts_planted_faults(tmp_path, package_sources):
    files, vectors = package_sources
    (tmp_path / "ok").mkdir()
    assert run(build(tmp_path / "ok", files)) == (0, 0)
    # flip the top mantissa bit (bit 22) of the first hidden-layer weight W1'[0][0] (folded)
    nn = files["stare_nn.c"]
    m = re.compile(r"0x1\.([0-9a-f])").search(nn, nn.index("/* W1' */"))
    bad = dict(files, **{"stare_nn.c": nn[:m.start(1)] + format(int(m.group(1), 16) ^ 8, "x") + nn[m.end(1):]})
    (tmp_path / "bad").mkdir()
    mismatches, env = run(build(tmp_path / "bad", bad))
    assert env == 0 and mismatches > 0


# every MXCSR bit the ICD names is caught: FTZ (bit 0), DAZ (bit 4, issue 25), the rounding control
@pytest.mark.parametrize("mode, bits", [("z", 1 | 16), ("f", 1), ("a", 16), ("t", 2 | 4), ("d", 2), ("u", 4)])
def test_fp_environment_checks(tmp_path, package_sources, mode, bits):
    files, _ = package_sources
    mismatches, env = run(build(tmp_path, files), mode)
    assert env == bits
    assert mismatches >= bin(bits).count("1")


def test_contraction_is_caught_in_the_selftest_unit(tmp_path, package_sources):
    if "fma" not in open("/proc/cpuinfo").read():
        pytest.fail("this test needs an x86-64 CPU with FMA (every CI machine here has it)")
    files, _ = package_sources
    _, env = run(build(tmp_path, files, flags=("-mfma", "-ffp-contract=fast")))
    assert env & 8


def test_layout_helpers():
    from codegen.units.controller.emit import STATE_DTYPE
    assert field_elements(STATE_DTYPE) == ["integral[0]", "integral[1]", "integral[2]", "mode", "clean", "fault"]


def test_bad_requests(units):
    c, t = units
    with pytest.raises(CodegenError, match="vectors must be in"):
        make_vectors(c, 0)
    with pytest.raises(CodegenError, match="first unit must be the stateful controller"):
        selftest_sources("stare", [make_vectors(configure_unit("network", artifact=random_artifact((12, 4, 3))), 4)])
    with pytest.raises(CodegenError, match=r"entry name 'Bad\*/'"):
        selftest_sources("Bad*/", [make_vectors(c, 4)])
