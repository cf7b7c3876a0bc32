"""The flight package on a firmware team's compilers (issue 25, defects 17-19): built with its own
CMakeLists by gcc and clang for x86-64 and the STM32F417 (clang --target=thumbv7em-none-eabihf,
run in the emulator), self-test 0 mismatching words on all four; math errno refused by name;
the C99 fallbacks of the GCC builtins give the same self-test words; nothing GNU-only reaches a
compiler that does not define __GNUC__."""
from __future__ import annotations

import re
import subprocess
from pathlib import Path

import pytest

from codegen.artifact import random_artifact
from firmware.flags import PORTABLE
from firmware.package_build import build_image
from host.control.nn_controller import default_package_config
from host.sim.scenarios import package_units
from tools.package import EvidencePlan, build_package
from tools.package_run import run_arm, run_x86

PLAN = EvidencePlan(gate_vectors=200, gate_sequences=1, sequence_steps=20, selftest_vectors=64, cycles_per_class=1)
ARTIFACT = random_artifact((12, 40, 3), seed=3)
READELF = {"x86": "readelf", "arm": "arm-none-eabi-readelf"}
OBJDUMP = {"x86": "objdump", "arm": "arm-none-eabi-objdump"}
SQRT_INSN = {"x86": "sqrtss", "arm": "vsqrt.f32"}
GNU_ONLY = re.compile(r"__builtin_\w+|__attribute__|__asm__|__extension__|__typeof__")


@pytest.fixture(scope="module")
def package(tmp_path_factory):
    cfg = default_package_config()
    units = package_units(cfg, ARTIFACT, None)
    return build_package(tmp_path_factory.mktemp("pkg") / "stare", cfg.name, units, cfg.to_mapping(),
                         {"network": {"sha256": ARTIFACT.sha256}}, PLAN, log=lambda _line: None).folder


def selftest(image: Path, target: str) -> int:
    return run_x86(image) if target == "x86" else run_arm(image, "stare").mismatches


def built_by(image: Path, target: str) -> str:
    """The .comment section: which compiler produced the image's code."""
    return subprocess.run([READELF[target], "-p", ".comment", str(image)], capture_output=True, text=True,
                          check=True).stdout


@pytest.mark.parametrize("target", ["x86", "arm"])
@pytest.mark.parametrize("compiler", ["gcc", "clang"])
def test_package_builds_and_selftests_with_each_compiler(package, tmp_path, compiler, target):
    image = build_image(package, "stare", target, tmp_path / "build", compiler=compiler)
    assert ("clang version" in built_by(image, target)) == (compiler == "clang")
    assert selftest(image, target) == 0


@pytest.mark.parametrize("target", ["x86", "arm"])
def test_c99_fallbacks_give_the_same_selftest_words(package, tmp_path, target):
    """-DSG_NO_BUILTINS (as a compiler without GCC's builtins builds it): no sqrt instruction left,
    the integer root instead, and still every self-test word."""
    image = build_image(package, "stare", target, tmp_path / "build", c_flags=["-DSG_NO_BUILTINS"])
    asm = subprocess.run([OBJDUMP[target], "-d", str(image)], capture_output=True, text=True, check=True).stdout
    assert SQRT_INSN[target] not in asm and "sg_sqrtf_c99" in asm
    assert selftest(image, target) == 0


@pytest.mark.parametrize("cc", ["gcc", "clang"])
def test_math_errno_is_refused_by_name(package, tmp_path, cc):
    """Built without the package's CMakeLists and with math errno on, every flight source stops
    with a message naming -fno-math-errno (else __builtin_sqrtf would call libm's sqrtf)."""
    flags = [f for f in PORTABLE if f != "-fno-math-errno"] + ["-fmath-errno"]
    for src in sorted((package / "src").glob("*.c")):
        res = subprocess.run([cc, *flags, "-I", str(package / "include"), "-c", str(src), "-o",
                              str(tmp_path / "a.o")], capture_output=True, text=True)
        assert res.returncode != 0 and "build with -fno-math-errno" in res.stderr, (src.name, res.stderr)


def test_nothing_gnu_only_reaches_a_compiler_without_gnu_c(package):
    """What a C99 compiler that is not GCC-compatible sees (no __GNUC__, no __clang__): no builtin,
    attribute or asm left in the package's own lines."""
    for src in sorted([*(package / "src").glob("*.c"), *(package / "selftest").glob("*.c")]):
        text = subprocess.run(["gcc", "-std=c99", "-U__GNUC__", "-I", str(package / "include"), "-I",
                               str(package / "selftest"), "-E", str(src)], capture_output=True, text=True,
                              check=True).stdout
        own, found = False, set()
        for line in text.splitlines():
            marker = re.match(r'# \d+ "([^"]*)"', line)
            if marker:
                own = str(package) in str(Path(src.parent, marker.group(1)).resolve())
            elif own:
                found |= set(GNU_ONLY.findall(line))
        assert found == set(), (src.name, found)
