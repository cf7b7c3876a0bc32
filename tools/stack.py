"""Worst-case stack: GCC's -fstack-usage frames plus the call graph read from the ELF's code.

Edges are direct calls (BL/BLX immediate) and jumps into another function's first instruction
(tail calls, counted as calls: an upper bound, since the caller's frame is already released).
A function without a .su entry (assembly, libgcc) gets its frame from its prologue (PUSH,
VPUSH, SUB SP). Indirect calls, recursion and dynamic frames make the bound unknown, and the
result says so. The emulator's stack painting (tools/m4/machine.py) gives the measured depth;
the static bound must not be below it.
"""
from __future__ import annotations

import re
from dataclasses import dataclass, field
from functools import lru_cache
from pathlib import Path

from capstone import arm_const as A

from tools.errors import ToolError
from tools.m4.decode import Decoder
from tools.m4.elf import Image
from tools.m4.machine import FLASH

_SU_LINE = re.compile(r"^(?P<loc>.*):(?P<func>[^:\s]+)\s+(?P<bytes>\d+)\s+(?P<kind>[\w,]+)\s*$")


@dataclass
class StackBound:
    entry: str
    bytes: int | None                 # None when unbounded or unknown
    path: list[str]                   # the deepest call chain
    frames: dict[str, int]            # frame of every function on any path from entry
    problems: list[str] = field(default_factory=list)


def read_su(files) -> dict[str, tuple[int, str]]:
    """{function: (bytes, static|dynamic|bounded)} from GCC .su files."""
    out = {}
    for path in files:
        for line in Path(path).read_text(errors="replace").splitlines():
            m = _SU_LINE.match(line.strip())
            if m:
                out[m.group("func")] = (int(m.group("bytes")), m.group("kind"))
    return out


def _prologue_frame(dec: Decoder, start: int, size: int) -> int:
    """Bytes pushed by a hand-written prologue: PUSH/VPUSH/SUB SP among the first instructions."""
    total = 0
    for ins in dec.linear(start, min(size, 24))[:6]:
        words = ins.text.split(None, 1)
        op = words[0].split(".")[0]
        if op in ("push", "vpush"):
            regs = re.findall(r"\b([rsd]\d+|lr|ip|fp|sl|sb)\b", words[1])
            total += sum(8 if r.startswith("d") else 4 for r in regs)
        elif op in ("sub", "subw") and words[1].startswith("sp, sp, #"):
            total += int(words[1].rsplit("#", 1)[1], 0)
    return total


def call_graph(image: Image) -> tuple[dict[str, set[str]], dict[str, list[str]]]:
    """{caller: callees} and {function: [indirect call sites]} by decoding each function."""
    dec = Decoder(image, (FLASH[0], FLASH[0] + FLASH[1]))
    cs = dec.cs
    starts = {f.start: f.name for f in image.functions}
    graph: dict[str, set[str]] = {}
    indirect: dict[str, list[str]] = {}
    for f in image.functions:
        if not FLASH[0] <= f.start < FLASH[0] + FLASH[1] or f.size == 0:
            continue
        callees = graph.setdefault(f.name, set())
        for insn in (i for addr, size in image.code_ranges(f.start, f.size)
                     for i in cs.disasm(image.read(addr, size), addr)):
            target = _branch_target(insn)
            if insn.id == A.ARM_INS_BLX and target is None:
                indirect.setdefault(f.name, []).append(f"0x{insn.address:08x}")
            if target is None:
                continue
            if insn.id in (A.ARM_INS_BL, A.ARM_INS_BLX) and target in starts:
                callees.add(starts[target])
            elif insn.id in (A.ARM_INS_B, A.ARM_INS_CBZ, A.ARM_INS_CBNZ) and target in starts \
                    and starts[target] != f.name:
                callees.add(starts[target])
    return graph, indirect


def _branch_target(insn) -> int | None:
    if insn.id not in (A.ARM_INS_BL, A.ARM_INS_BLX, A.ARM_INS_B, A.ARM_INS_CBZ, A.ARM_INS_CBNZ):
        return None
    imms = [op.imm for op in insn.operands if op.type == A.ARM_OP_IMM]
    return (imms[-1] & ~1) if imms else None


def worst_case(image: Image, su_files, entry: str) -> StackBound:
    """Deepest stack of `entry` and everything it calls, in bytes (SP at the call = 0)."""
    image.function(entry)
    su = read_su(su_files)
    graph, indirect = call_graph(image)
    dec = Decoder(image, (FLASH[0], FLASH[0] + FLASH[1]))
    problems: list[str] = []
    frames: dict[str, int] = {}

    def frame(name: str) -> int:
        if name not in frames:
            if name in su:
                size, kind = su[name]
                if kind != "static":
                    problems.append(f"{name}: {kind} stack frame")
            else:
                f = image.function(name)
                size = _prologue_frame(dec, f.start, f.size)
            frames[name] = size
        return frames[name]

    @lru_cache(maxsize=None)
    def deepest(name: str, trail: tuple) -> tuple[int, tuple]:
        if name in trail:
            problems.append(f"recursion: {' -> '.join(trail + (name,))}")
            return 0, (name,)
        if name in indirect:
            problems.append(f"{name}: indirect call at {', '.join(indirect[name])}")
        best, best_path = 0, ()
        for callee in sorted(graph.get(name, ())):
            depth, path = deepest(callee, trail + (name,))
            if depth > best:
                best, best_path = depth, path
        return frame(name) + best, (name,) + best_path

    depth, path = deepest(entry, ())
    problems = sorted(set(problems))
    return StackBound(entry, None if problems else depth, list(path), frames, problems)


def check_against_paint(bound: StackBound, painted: int) -> None:
    """The static bound must cover what the emulator measured."""
    if bound.bytes is not None and painted > bound.bytes:
        raise ToolError(f"stack of {bound.entry}: painted {painted} B exceeds the static bound "
                        f"{bound.bytes} B (call graph incomplete?)")
