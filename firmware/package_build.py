"""A flight package built the way a firmware team builds it: with its own CMakeLists.txt, added
by firmware/package_image (a main that runs `<name>_selftest()` and one reference step), for the
STM32F417 (arm-none-eabi-gcc, firmware/startup.c and stm32f417.ld) or for x86-64 (host gcc).

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
TARGETS = ("arm", "x86")
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


def build_image(package_dir: str | Path, name: str, target: str, build_dir: str | Path,
                c_flags: Sequence[str] = ()) -> Path:
    """Configure and build the image of `package_dir` for `target`; returns the ELF (arm) or the
    executable (x86). `c_flags` are appended to the project's CMAKE_C_FLAGS (a test passes a fast-math flag to see the guard)."""
    if target not in TARGETS:
        raise FirmwareError(f"package build: unknown target {target!r} (choose from {', '.join(TARGETS)})")
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
    cmd = [cmake, "-S", str(IMAGE_PROJECT), "-B", str(build_dir), f"-DSG_PACKAGE_DIR={package_dir}",
           f"-DSG_PACKAGE_NAME={name}", f"-DSG_TARGET={target}", f"-DSG_EXTRA_C_FLAGS={' '.join(c_flags)}"]
    if target == "arm":
        if shutil.which("arm-none-eabi-gcc") is None:
            raise FirmwareError("package build: 'arm-none-eabi-gcc' not found on PATH (see tools/setup.sh)")
        cmd.append(f"-DCMAKE_TOOLCHAIN_FILE={TOOLCHAIN}")
    else:
        cmd.append("-DCMAKE_C_COMPILER=gcc")
    _run(cmd, "configure")
    _run([cmake, "--build", str(build_dir), "--", "-j2"], "compile")
    image = build_dir / ("image.elf" if target == "arm" else "image")
    if not image.is_file():
        raise FirmwareError(f"package build: {image.name} was not produced")
    return image
