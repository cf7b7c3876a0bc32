"""A flight package built the way a firmware team builds it: with its own CMakeLists.txt, added
by firmware/package_image (a main that runs `<name>_selftest()` and one reference step), for the
STM32F417 (arm-none-eabi-gcc, firmware/startup.c and stm32f417.ld), for QEMU's netduinoplus2
(the same, reporting by semihosting, with CCM moved into SRAM: see `qemu_linker_script`) or for
x86-64 (host gcc).

No cache: this is the end-to-end check of the package as delivered, run at generation, by
`staregen package check --run` and by the tests.
"""
from __future__ import annotations

import os
import re
import shutil
import subprocess
from pathlib import Path
from typing import Sequence

from codegen.names import name_problem, show
from firmware.errors import FirmwareError

HERE = Path(__file__).resolve().parent
IMAGE_PROJECT = HERE / "package_image"
TOOLCHAIN = IMAGE_PROJECT / "toolchain-arm-none-eabi.cmake"
LINKER_SCRIPT = HERE / "stm32f417.ld"
TARGETS = ("arm", "qemu", "x86")
COMPILERS = ("gcc", "clang")
# compiler -> the toolchain file of the STM32F417 image and the programs it needs (x86: CMAKE_C_COMPILER).
_ARM_TOOLCHAINS = {"gcc": (TOOLCHAIN, ("arm-none-eabi-gcc",)),
                   "clang": (IMAGE_PROJECT / "toolchain-clang-arm.cmake", ("clang", "arm-none-eabi-gcc"))}
# QEMU 7.2's netduinoplus2 (STM32F405) maps no CCM at 0x10000000 (`info mtree`: flash, 192 KB of SRAM
# at 0x20000000, peripherals): its image keeps the constant tables in the top 64 KB of that SRAM,
# above the 128 KB the STM32F417 map uses, so the copy to RAM and its CRC run as on the board.
CCM_REGION = "CCM   (rw)  : ORIGIN = 0x10000000, LENGTH = 64K"
QEMU_CCM_REGION = "CCM   (rw)  : ORIGIN = 0x20020000, LENGTH = 64K"
_FLAG = re.compile(r"-[A-Za-z0-9_=+.,-]+")


def _cmake() -> str:
    path = shutil.which("cmake")
    if path is None:
        raise FirmwareError("package build: 'cmake' not found on PATH (install Debian's cmake, see tools/setup.sh)")
    return path


def _first_error(text: str) -> str:
    lines = [ln.strip() for ln in text.splitlines() if ln.strip()]
    for pattern in ("#error", "error:", "Error", "undefined reference"):
        hits = [ln for ln in lines if pattern in ln]
        if hits:
            return hits[0]
    return lines[-1] if lines else "(no output)"


def _run(cmd: list[str], what: str) -> None:
    env = dict(os.environ, LC_ALL="C")
    res = subprocess.run(cmd, capture_output=True, text=True, check=False, env=env)
    if res.returncode != 0:
        raise FirmwareError(f"package build ({what}): {_first_error(res.stdout + res.stderr)}")


def qemu_linker_script(build_dir: Path) -> Path:
    """stm32f417.ld with CCM moved to QEMU's SRAM (above), written into `build_dir`."""
    text = LINKER_SCRIPT.read_text()
    if text.count(CCM_REGION) != 1:
        raise FirmwareError(f"package build: {LINKER_SCRIPT.name} has no single line {CCM_REGION!r}")
    path = build_dir / "stm32f405_qemu.ld"
    path.write_text(text.replace(CCM_REGION, QEMU_CCM_REGION))
    return path


def _compiler_args(target: str, compiler: str) -> list[str]:
    """The CMake arguments that choose `compiler` for `target` (x86, or arm/qemu: an ARM image),
    after checking its programs exist."""
    toolchain, programs = _ARM_TOOLCHAINS[compiler] if target != "x86" else (None, (compiler,))
    for prog in programs:
        if shutil.which(prog) is None:
            raise FirmwareError(f"package build: {prog!r} not found on PATH (see tools/setup.sh)")
    return [f"-DCMAKE_TOOLCHAIN_FILE={toolchain}"] if toolchain else [f"-DCMAKE_C_COMPILER={compiler}"]


def build_image(package_dir: str | Path, name: str, target: str, build_dir: str | Path,
                c_flags: Sequence[str] = (), compiler: str = "gcc") -> Path:
    """Configure and build the image of `package_dir` for `target` with `compiler` (gcc or clang);
    returns the ELF (arm, qemu) or the executable (x86). `c_flags` are appended to the project's
    CMAKE_C_FLAGS (a test passes a fast-math flag to see the guard)."""
    if target not in TARGETS:
        raise FirmwareError(f"package build: unknown target {target!r} (choose from {', '.join(TARGETS)})")
    if compiler not in COMPILERS:
        raise FirmwareError(f"package build: unknown compiler {compiler!r} (choose from {', '.join(COMPILERS)})")
    problem = name_problem(name)
    if problem:
        raise FirmwareError(f"package build: package name {show(name)}: {problem}")
    for f in c_flags:
        if not _FLAG.fullmatch(f):
            raise FirmwareError(f"package build: {f!r} is not a plain compiler option")
    package_dir, build_dir = Path(package_dir).resolve(), Path(build_dir).resolve()
    if not (package_dir / "CMakeLists.txt").is_file():
        raise FirmwareError(f"package build: {package_dir} has no CMakeLists.txt")
    build_dir.mkdir(parents=True, exist_ok=True)
    cmake = _cmake()
    cmake_target = "x86" if target == "x86" else "arm"      # the QEMU image is an ARM image
    cmd = [cmake, "-S", str(IMAGE_PROJECT), "-B", str(build_dir), f"-DSG_PACKAGE_DIR={package_dir}",
           f"-DSG_PACKAGE_NAME={name}", f"-DSG_TARGET={cmake_target}", f"-DSG_EXTRA_C_FLAGS={' '.join(c_flags)}",
           *_compiler_args(target, compiler)]
    if target == "qemu":
        cmd += ["-DSG_SEMIHOSTING=ON", f"-DSG_LINKER_SCRIPT={qemu_linker_script(build_dir)}"]
    _run(cmd, "configure")
    _run([cmake, "--build", str(build_dir), "--", "-j2"], "compile")
    image = build_dir / ("image" if target == "x86" else "image.elf")
    if not image.is_file():
        raise FirmwareError(f"package build: {image.name} was not produced")
    return image
