"""Running a built flight-package image: the x86-64 executable natively, the STM32F417 ELF in
the Cortex-M4 emulator, where `<name>_selftest()` runs plainly and then the reference step
(`<name>_selftest_reference` + `<name>_step`, what main does after the self-test) runs under the
cycle profiler in every memory mode; and the QEMU image in QEMU's netduinoplus2 (STM32F405), a
second, independent emulator, which reports by semihosting and is killed past a time-out."""
from __future__ import annotations

import re
import shutil
import subprocess
import time
from dataclasses import dataclass, field
from pathlib import Path

from unicorn.arm_const import UC_ARM_REG_R0

from tools.errors import ToolError
from tools.m4.elf import Image
from tools.m4.machine import Machine
from tools.m4.profile import MODES, Profiler

SELFTEST_MAX_INSNS = 200_000_000
QEMU_TIMEOUT_S = 60.0
QEMU_MACHINE = "netduinoplus2"
_LINE = re.compile(r"selftest mismatches: (-?\d+)")
_WORDS = re.compile(r"reference output:((?: [0-9a-f]{8})+)\n")


@dataclass(frozen=True)
class ArmImageRun:
    mismatches: int
    step_cycles: dict[str, int]      # mode -> cycles of the reference step
    status: int                      # the reference step's status word
    output: tuple[str, ...] = ()     # the reference step's output record, one hex word each
    selftest_cycles: dict[str, int] = field(default_factory=dict)   # mode -> cycles of <name>_selftest()
    selftest_stack_bytes: int = 0    # stack <name>_selftest() used (painted)


@dataclass(frozen=True)
class QemuRun:
    mismatches: int
    output: tuple[str, ...]          # the reference step's output record, one hex word each
    seconds: float


def run_x86(exe: str | Path) -> int:
    """Mismatching words reported by the native image (its exit status says pass/fail too)."""
    try:
        res = subprocess.run([str(exe)], capture_output=True, text=True, timeout=600, check=False)
    except (OSError, subprocess.TimeoutExpired) as exc:
        raise ToolError(f"package image {Path(exe).name}: cannot run ({exc})") from None
    m = _LINE.search(res.stdout)
    if m is None or res.returncode not in (0, 1):
        raise ToolError(f"package image {Path(exe).name}: no self-test result (exit {res.returncode})")
    mismatches = int(m.group(1))
    if (mismatches == 0) != (res.returncode == 0):
        raise ToolError(f"package image {Path(exe).name}: exit status {res.returncode} contradicts {mismatches} mismatches")
    return mismatches


def run_arm(elf: str | Path, name: str) -> ArmImageRun:
    """main() in the emulator (the self-test, then one reference step); then the reference step
    alone under the cycle profiler (ideal, art, pessimistic), on records in SRAM."""
    image = Image(elf)
    plain = Machine(image)
    plain.boot()
    plain.call("main", max_insns=SELFTEST_MAX_INSNS)
    mismatches = int.from_bytes(plain.read(image.symbol("sg_image_result"), 4), "little", signed=True)
    status = int.from_bytes(plain.read(image.symbol("sg_image_status"), 4), "little")
    output = _output_words(plain, image)
    prof = Profiler(image, f"{name}_step")
    prof.machine.boot()
    state, inp, out = (image.symbol("_sarena") + off for off in (0, 0x400, 0x800))   # records of < 1 KB each
    prof.machine.call(f"{name}_selftest_reference", (state, inp), max_insns=100_000)
    prof.evaluations.clear()
    prof.run(f"{name}_step", (state, inp, out), max_insns=10_000_000)
    if len(prof.evaluations) != 1:
        raise ToolError(f"{Path(elf).name}: {len(prof.evaluations)} evaluations of {name}_step for one call")
    ref = prof.evaluations[0]
    cycles, stack = selftest_profile(image, name, mismatches)
    return ArmImageRun(mismatches, {m: int(ref.total[i]) for i, m in enumerate(MODES)}, status, output,
                       selftest_cycles=cycles, selftest_stack_bytes=stack)


def _output_words(machine: Machine, image: Image) -> tuple[str, ...]:
    n = int.from_bytes(machine.read(image.symbol("sg_image_output_words"), 4), "little")
    if not 1 <= n <= 256:
        raise ToolError(f"{image.path.name}: sg_image_output_words is {n}")
    raw = machine.read(image.symbol("sg_image_output"), 4 * n)
    return tuple(f"{int.from_bytes(raw[i:i + 4], 'little'):08x}" for i in range(0, 4 * n, 4))


def qemu_command(elf: str | Path) -> list[str]:
    exe = shutil.which("qemu-system-arm")
    if exe is None:
        raise ToolError("qemu-system-arm not found on PATH (Debian's qemu-system-arm; see tools/setup.sh)")
    # semihosting lets the image ask the host for a shell command (SYS_SYSTEM): the seccomp sandbox
    # denies QEMU any new process, whatever the image asks
    return [exe, "-M", QEMU_MACHINE, "-nodefaults", "-display", "none", "-monitor", "none", "-serial", "null",
            "-sandbox", "on,obsolete=deny,elevateprivileges=deny,spawn=deny,resourcecontrol=deny",
            "-semihosting-config", "enable=on,target=native", "-kernel", str(elf)]


def run_qemu(elf: str | Path, timeout: float = QEMU_TIMEOUT_S) -> QemuRun:
    """The QEMU image (firmware/package_build.py, target qemu) in QEMU's netduinoplus2: main runs
    the self-test and one reference step and prints both by semihosting, then exits by SYS_EXIT.
    QEMU is killed after `timeout` seconds (a hung image must not hang the caller)."""
    t0 = time.perf_counter()
    try:
        res = subprocess.run(qemu_command(elf), capture_output=True, text=True, timeout=timeout,
                             stdin=subprocess.DEVNULL, cwd=Path(elf).parent, check=False)
    except subprocess.TimeoutExpired:
        raise ToolError(f"qemu: {Path(elf).name} did not finish within {timeout:g} s (killed)") from None
    except OSError as exc:
        raise ToolError(f"qemu: cannot run ({exc.strerror or exc})") from None
    seconds = time.perf_counter() - t0
    text = res.stdout + res.stderr          # QEMU writes the semihosting console to stderr
    m, words = _LINE.search(text), _WORDS.search(text)
    if m is None or words is None or res.returncode not in (0, 1):
        tail = (res.stderr.strip().splitlines() or ["no output"])[-1][:200]
        raise ToolError(f"qemu: {Path(elf).name}: no self-test result (exit {res.returncode}; {tail})")
    mismatches = int(m.group(1))
    if (mismatches == 0) != (res.returncode == 0):
        raise ToolError(f"qemu: exit status {res.returncode} contradicts {mismatches} mismatches")
    return QemuRun(mismatches, tuple(words.group(1).split()), round(seconds, 2))


def selftest_profile(image: Image, name: str, mismatches: int) -> tuple[dict[str, int], int]:
    """`<name>_selftest()` once more under the cycle profiler on a painted stack: its cycles per
    mode and the stack it used (the ICD's start-up figures); it must return what main saw."""
    prof = Profiler(image, f"{name}_selftest")
    prof.machine.boot()
    prof.machine.paint_stack()
    cycles = prof.run(f"{name}_selftest", max_insns=SELFTEST_MAX_INSNS)
    r0 = prof.machine.uc.reg_read(UC_ARM_REG_R0)
    again = r0 - (1 << 32) if r0 >= 1 << 31 else r0
    if again != mismatches:
        raise ToolError(f"{image.path.name}: {name}_selftest returned {again} under the profiler, {mismatches} in main")
    return dict(zip(MODES, map(int, cycles))), prof.machine.stack_top - prof.machine.lowest_stack_write()
