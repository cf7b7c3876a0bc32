"""Host side of the firmware harness (firmware/harness.h): records in, records out, in batches.

SRAM is 128 KB, so records go through the linker's arena (`_sarena`.. `_earena`, 96 KB) in
batches: inputs packed at the start, outputs right after them, then harness_run(in, out, n).
No per-instruction hook is installed here (the fast path of the bit-exact gate); every batch is
still capped in instructions, so a runaway entry point ends in a ToolError.
"""
from __future__ import annotations

import os

import numpy as np

from tools.errors import ToolError
from tools.m4.elf import Image
from tools.m4.machine import Machine

# Instruction cap per record; the network path needs a few thousand.
MAX_INSNS_PER_RECORD = 1_000_000


class Harness:
    def __init__(self, elf: str | os.PathLike | Image, machine: Machine | None = None,
                 max_insns_per_record: int = MAX_INSNS_PER_RECORD):
        self.image = elf if isinstance(elf, Image) else Image(elf)
        for name in ("harness_run", "harness_reset", "system_init", "adapter_in_bytes",
                     "adapter_out_bytes", "_sarena", "_earena"):
            self.image.symbol(name)  # a clear ToolError if the ELF is not a harness build
        self.in_bytes = self.image.word("adapter_in_bytes")
        self.out_bytes = self.image.word("adapter_out_bytes")
        if self.in_bytes == 0 or self.in_bytes % 4 or self.out_bytes % 4:
            raise ToolError(f"{self.image.path.name}: bad record sizes "
                            f"(in {self.in_bytes} B, out {self.out_bytes} B)")
        self.arena = self.image.symbol("_sarena")
        self.capacity = (self.image.symbol("_earena") - self.arena) // (self.in_bytes + self.out_bytes)
        self.max_insns_per_record = max_insns_per_record
        self.machine = machine or Machine(self.image)
        self.machine.boot()
        self.reset()

    def reset(self, runner=None) -> None:
        """Re-initialise the adapter's controller state (harness_reset)."""
        (runner or self._call)("harness_reset", (), self.max_insns_per_record)

    def run_batch(self, records: np.ndarray, runner=None) -> np.ndarray:
        """One batch (at most self.capacity records) through harness_run; `runner(fn, args,
        max_insns)` replaces the plain call (the cycle profiler passes its own)."""
        n = records.shape[0]
        out_addr = self.arena + n * self.in_bytes
        self.machine.write(self.arena, records.tobytes())
        args = (self.arena, out_addr, n)
        cap = n * self.max_insns_per_record + 10_000
        (runner or self._call)("harness_run", args, cap)
        data = self.machine.read(out_addr, n * self.out_bytes)
        return np.frombuffer(data, dtype=np.uint8).reshape(n, self.out_bytes)

    def _call(self, fn, args, cap):
        self.machine.call(fn, args, max_insns=cap)

    def run(self, records: np.ndarray, runner=None) -> np.ndarray:
        """(N, in_bytes) uint8 -> (N, out_bytes) uint8, in batches that fit the arena."""
        if records.ndim != 2 or records.shape[1] != self.in_bytes or records.dtype != np.uint8:
            raise ValueError(f"harness: records must be uint8 (N, {self.in_bytes}), got "
                             f"{records.dtype} {records.shape}")
        out = np.empty((records.shape[0], self.out_bytes), dtype=np.uint8)
        for lo in range(0, records.shape[0], self.capacity):
            hi = min(lo + self.capacity, records.shape[0])
            out[lo:hi] = self.run_batch(np.ascontiguousarray(records[lo:hi]), runner)
        return out
