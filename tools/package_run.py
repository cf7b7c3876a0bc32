"""Running a built flight-package image: the x86-64 executable natively, the STM32F417 ELF in
the Cortex-M4 emulator, where `<name>_selftest()` runs plainly and then the reference step
(`<name>_selftest_reference` + `<name>_step`, what main does after the self-test) runs under the
cycle profiler in every memory mode."""
from __future__ import annotations

import re
import subprocess
from dataclasses import dataclass, field
from pathlib import Path

from unicorn.arm_const import UC_ARM_REG_R0

from tools.errors import ToolError
from tools.m4.elf import Image
from tools.m4.machine import Machine
from tools.m4.profile import MODES, Profiler

SELFTEST_MAX_INSNS = 200_000_000
_LINE = re.compile(r"selftest mismatches: (-?\d+)")


@dataclass(frozen=True)
class ArmImageRun:
    mismatches: int
    step_cycles: dict[str, int]      # mode -> cycles of the reference step
    status: int                      # the reference step's status word
    selftest_cycles: dict[str, int] = field(default_factory=dict)   # mode -> cycles of <name>_selftest()
    selftest_stack_bytes: int = 0    # stack <name>_selftest() used (painted)


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
    return ArmImageRun(mismatches, {m: int(ref.total[i]) for i, m in enumerate(MODES)}, status, cycles, stack)


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
