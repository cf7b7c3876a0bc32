"""The STM32F417 as Unicorn sees it: memory map, ELF load, function calls, faults, stack paint.

A function is called by pointing LR at a mapped magic address (|1 for Thumb) and running until
the PC reaches it. Every run is capped in instructions, so a runaway loop ends in a ToolError.
Hooks (the cycle profiler's) are installed by the `install` callback before the first run:
Unicorn only instruments code translated after a hook exists.
"""
from __future__ import annotations

from typing import Callable

from unicorn import (UC_ARCH_ARM, UC_HOOK_INTR, UC_HOOK_MEM_INVALID, UC_MODE_MCLASS,
                     UC_MODE_THUMB, UC_PROT_ALL, UC_PROT_EXEC, UC_PROT_READ, Uc, UcError)
from unicorn import arm_const as R

from tools.errors import ToolError
from tools.m4.elf import Image

FLASH = (0x08000000, 1024 << 10)
SRAM = (0x20000000, 128 << 10)
CCM = (0x10000000, 64 << 10)
# Unicorn models no System Control Space device (NVIC/SCB): map its page as plain memory so
# startup's CPACR/FPDSCR writes land somewhere checkable. Its M4 FPU is usable from reset.
SCS = (0xE000E000, 0x1000)
SCB_CPACR = 0xE000ED88
CPACR_CP10_CP11 = 0xF << 20
# Return address of every host call: a reserved hole of the STM32F4 map, mapped, never executed.
MAGIC = 0x0F000000

FPSCR_POISON = (1 << 24) | (1 << 25) | (3 << 22)
# `vmsr fpscr, r0; bx lr`, placed in the MAGIC page: Unicorn's register write of FPSCR does not
# update every mode the FPU computes with (default-NaN mode stays off), the instruction does.
_SET_FPSCR = MAGIC + 0x100
_SET_FPSCR_CODE = bytes.fromhex("e1ee100a7047")
STACK_PAINT = 0xA5A5A5A5
DEFAULT_MAX_INSNS = 5_000_000

_REG_ARGS = (R.UC_ARM_REG_R0, R.UC_ARM_REG_R1, R.UC_ARM_REG_R2, R.UC_ARM_REG_R3)


class Machine:
    def __init__(self, image: Image, install: Callable[[Uc], None] | None = None):
        self.image = image
        self.uc = uc = Uc(UC_ARCH_ARM, UC_MODE_THUMB | UC_MODE_MCLASS)
        uc.ctl_set_cpu_model(R.UC_CPU_ARM_CORTEX_M4)  # without it Unicorn emulates an M33
        uc.mem_map(FLASH[0], FLASH[1], UC_PROT_READ | UC_PROT_EXEC)
        for base, size in (SRAM, CCM, SCS):
            uc.mem_map(base, size, UC_PROT_ALL)
        uc.mem_map(MAGIC, 0x1000, UC_PROT_READ | UC_PROT_EXEC)
        for seg in image.segments:
            try:
                uc.mem_write(seg.addr, seg.data)
            except UcError:
                raise ToolError(f"{image.path.name}: segment at 0x{seg.addr:08x} "
                                f"({len(seg.data)} B) is outside the STM32F417 memory map") from None
        self.stack_top = image.symbol("_estack")
        self._stop_reason: str | None = None
        uc.hook_add(UC_HOOK_INTR, self._on_intr)
        uc.hook_add(UC_HOOK_MEM_INVALID, self._on_bad_mem)
        if install is not None:
            install(uc)

    # --- hooks that only fire on trouble -------------------------------------------------
    def _on_intr(self, uc, intno, _data):
        self._stop_reason = f"exception {intno} (breakpoint or fault handler)"
        uc.emu_stop()

    def _on_bad_mem(self, uc, access, addr, size, _value, _data):
        self._stop_reason = f"invalid memory access of {size} B at 0x{addr:08x}"
        return False

    # --- calls ---------------------------------------------------------------------------
    def where(self, pc: int) -> str:
        i = self.image.function_index(pc)
        if i < 0:
            return f"0x{pc:08x}"
        f = self.image.functions[i]
        return f"0x{pc:08x} ({f.name}+0x{pc - f.start:x})"

    def call(self, fn: str | int, args: tuple = (), max_insns: int = DEFAULT_MAX_INSNS,
             sp: int | None = None) -> int:
        """Run fn(args...) to its return; returns r0. Raises ToolError on any fault or runaway."""
        addr = self.image.symbol(fn) if isinstance(fn, str) else fn
        name = fn if isinstance(fn, str) else self.where(fn)
        uc = self.uc
        for reg, val in zip(_REG_ARGS, args):
            uc.reg_write(reg, val & 0xFFFFFFFF)
        uc.reg_write(R.UC_ARM_REG_SP, self.stack_top if sp is None else sp)
        uc.reg_write(R.UC_ARM_REG_LR, MAGIC | 1)
        self._stop_reason = None
        try:
            uc.emu_start(addr | 1, MAGIC, count=max_insns)
        except UcError as exc:
            pc = uc.reg_read(R.UC_ARM_REG_PC)
            why = self._stop_reason or str(exc)
            raise ToolError(f"emulator fault in {name}: {why} near pc {self.where(pc)}") from None
        pc = uc.reg_read(R.UC_ARM_REG_PC)
        if pc != MAGIC:
            if self._stop_reason:
                raise ToolError(f"{name} stopped: {self._stop_reason} at pc {self.where(pc)}")
            raise ToolError(f"{name} did not return within {max_insns} instructions "
                            f"(runaway loop?), pc {self.where(pc)}")
        return uc.reg_read(R.UC_ARM_REG_R0)

    def boot(self) -> None:
        """Run the firmware's system_init (.data/.bss, FPU on, FPSCR) and check its effect.

        FPSCR is poisoned first (flush-to-zero, default NaN, round towards zero) so that a
        startup which does not set it fails here rather than passing on Unicorn's reset value."""
        self.uc.reg_write(R.UC_ARM_REG_FPSCR, FPSCR_POISON)
        self.call("system_init", max_insns=200_000)
        cpacr = int.from_bytes(self.uc.mem_read(SCB_CPACR, 4), "little")
        fpscr = self.uc.reg_read(R.UC_ARM_REG_FPSCR)
        if cpacr & CPACR_CP10_CP11 != CPACR_CP10_CP11 or fpscr & 0x07C00000:
            raise ToolError(f"startup did not enable the FPU as required "
                            f"(CPACR 0x{cpacr:08x}, FPSCR 0x{fpscr:08x})")

    def set_fpscr(self, value: int) -> None:
        """Set FPSCR as start-up code would (VMSR), e.g. to see what the self-test makes of
        flush-to-zero, default-NaN or a directed rounding mode."""
        self.uc.mem_write(_SET_FPSCR, _SET_FPSCR_CODE)
        self.call(_SET_FPSCR, (value,), max_insns=10)
        got = self.uc.reg_read(R.UC_ARM_REG_FPSCR) & 0x07C00000
        if got != value & 0x07C00000:
            raise ToolError(f"FPSCR reads 0x{got:08x} after writing 0x{value:08x}")

    # --- memory --------------------------------------------------------------------------
    def write(self, addr: int, data: bytes) -> None:
        self.uc.mem_write(addr, data)

    def read(self, addr: int, size: int) -> bytes:
        return bytes(self.uc.mem_read(addr, size))

    def paint_stack(self) -> None:
        lo = self.image.symbol("_sstack")
        self.uc.mem_write(lo, STACK_PAINT.to_bytes(4, "little") * ((self.stack_top - lo) // 4))

    def lowest_stack_write(self) -> int:
        """Lowest stack address written since paint_stack (the stack top if none)."""
        lo = self.image.symbol("_sstack")
        mem = self.read(lo, self.stack_top - lo)
        pattern = STACK_PAINT.to_bytes(4, "little")
        for off in range(0, len(mem), 4):
            if mem[off:off + 4] != pattern:
                return lo + off
        return self.stack_top
