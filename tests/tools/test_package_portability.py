"""The flight package on a firmware team's compilers (issue 25, defects 17-19): built with its own
CMakeLists by gcc and clang for x86-64 and the STM32F417 (clang --target=thumbv7em-none-eabihf,
run in the emulator), self-test 0 mismatching words on all four; math errno refused by name;
the C99 fallbacks of the GCC builtins give the same self-test words; nothing GNU-only reaches a
compiler that does not define __GNUC__."""
from __future__ import annotations

import json
import re
import subprocess
from pathlib import Path

import pytest

from codegen.artifact import random_artifact
from firmware.flags import ARM_CC, ARM_CPU, CLANG_ARM_TARGET, GCC_ONLY, PORTABLE
from firmware.package_build import build_image
from host.control.nn_controller import default_package_config
from host.sim.scenarios import package_units
from tools.m4.elf import Image
from tools.m4.machine import Machine
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


def test_icd_states_what_the_manifest_measured(package, tmp_path):
    """The generated ICD (defect 21) states the manifest's reference output words (and the STM32F417
    image's reference step, run here, writes exactly them), record sizes, and the self-test's
    cycles and stack measured in the emulator."""
    doc = json.loads((package / "manifest.json").read_text())
    icd = (package / "ICD.md").read_text()
    ev = doc["evidence"]["units"]["controller"]
    words = ev["selftest_vectors"]["reference_output_words"]
    assert f"`{' '.join(words)}`" in icd
    sizes = ev["memory"]["record_bytes"]
    assert sizes == {"input": 64, "output": 4 * len(words), "state": 24}
    for role, n in sizes.items():
        assert f"`sizeof(stare_{role}_t)` = {n} B" in icd
    arm = doc["evidence"]["package_build"]["arm"]
    assert arm["selftest_cycles"]["ideal"] > 10 * arm["reference_cycles"]["ideal"] and arm["selftest_stack_bytes"] > 0
    for mode, cycles in arm["selftest_cycles"].items():
        assert f"{cycles} cycles {mode}" in icd
    assert f"uses {arm['selftest_stack_bytes']} B of stack" in icd
    assert "stare_integrity_check(&stare_state)" in icd
    image = Image(build_image(package, "stare", "arm", tmp_path / "arm"))
    machine = Machine(image)
    machine.boot()
    state, inp, out = (image.symbol("_sarena") + off for off in (0, 0x400, 0x800))
    machine.call("stare_selftest_reference", (state, inp))
    machine.call("stare_step", (state, inp, out))
    got = [f"0x{int.from_bytes(machine.read(out + 4 * i, 4), 'little'):08x}" for i in range(len(words))]
    assert got == words


@pytest.mark.parametrize("compiler", ["gcc", "clang"])
def test_every_package_table_is_in_a_sg_tables_section(package, tmp_path, compiler):
    """The ICD's one-line CCM rule moves all the package's constant tables: the flight objects
    have no other read-only or writable data section (the self-test's vectors stay with .rodata)."""
    cc = [compiler, f"--target={CLANG_ARM_TARGET}"] if compiler == "clang" else [ARM_CC]
    flags = PORTABLE + (GCC_ONLY if compiler == "gcc" else [])
    for src in sorted((package / "src").glob("*.c")):
        obj = tmp_path / (src.stem + ".o")
        subprocess.run([*cc, *flags, *ARM_CPU, "-ffunction-sections", "-fdata-sections", "-DSG_FP_CONTRACT_OFF=1",
                        "-I", str(package / "include"), "-c", str(src), "-o", str(obj)], check=True)
        heads = subprocess.run(["arm-none-eabi-objdump", "-h", str(obj)], capture_output=True, text=True,
                               check=True).stdout
        data = {ln.split()[1]: int(ln.split()[2], 16) for ln in heads.splitlines()
                if re.match(r"\s*\d+ \.(rodata|data|bss|sg_tables)", ln)}
        assert {s for s, n in data.items() if n and not s.startswith(".sg_tables.")} == set(), (src.name, data)
    assert any(s.startswith(".sg_tables.") for s in data)
