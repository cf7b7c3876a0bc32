"""Cross-check of the cycle model's per-block costs against llvm-mca (a lower bound).

llvm-mca's Cortex-M4 scheduling model is an in-order, single-issue pipeline with perfect fetch,
no branch penalty and one cycle for every LDM/STM/PUSH/POP whatever the register count, so per
static basic block it should never exceed the model: mca <= lenient and mca <= strict.
"""
from __future__ import annotations

import os
import re
import shutil
import subprocess
from pathlib import Path

from tools.errors import ToolError
from tools.m4.elf import Image
from tools.m4.wcet import Analysis

MCA_ARGS = ("-mtriple=thumbv7em-none-eabihf", "-mcpu=cortex-m4", "-iterations=1")

# B, BL, BLX (any condition, any width) and CBZ/CBNZ: the ones whose last operand is a target.
_BRANCH = re.compile(r"^(?:(bl?x?)(?:eq|ne|cs|hs|cc|lo|mi|pl|vs|vc|hi|ls|ge|lt|gt|le|al)?(?:\.[wn])?|cbn?z)$")
_SUMMARY = re.compile(r"^Instructions:\s+(\d+)\nTotal Cycles:\s+(\d+)$", re.M)


def find_llvm_mca() -> str:
    """llvm-mca, else the newest llvm-mca-NN on PATH."""
    if shutil.which("llvm-mca"):
        return shutil.which("llvm-mca")
    found = sorted((int(m.group(1)), str(Path(d) / f.name))
                   for d in os.environ.get("PATH", "").split(os.pathsep) if Path(d).is_dir()
                   for f in Path(d).iterdir() if (m := re.fullmatch(r"llvm-mca-(\d+)", f.name)))
    if not found:
        raise ToolError("llvm-mca not found on PATH (Debian: apt-get install llvm)")
    return found[-1][1]


def _llvm_syntax(text: str) -> str:
    """Capstone's GNU text in a form llvm-mc parses. Hex immediates are accepted as they are; a
    branch target `#0x8000486` is read as an out-of-range offset, so it becomes an undefined
    label (llvm-mca never resolves fixups). BL/BLX become B/BX: llvm-mca charges any call a flat
    100-cycle latency ("call instructions are not correctly modeled"), whereas a branch costs
    what it would without the transfer, and the transfer itself is not modelled either way."""
    mnem, _, ops = text.partition(" ")
    m = _BRANCH.match(mnem)
    if not m:
        return text
    base = m.group(1) or ""
    if base in ("bl", "blx"):
        mnem = {"bl": "b", "blx": "bx"}[base] + mnem[len(base):]
    return f"{mnem} {re.sub(r'#-?0x[0-9a-f]+$', 'target', ops)}"


def blocks_cycles(blocks: list[list[str]]) -> list[int]:
    """Cycles of each block, all blocks in one llvm-mca process (one code region each: llvm-mca
    simulates every region from an empty pipeline)."""
    lines = []
    for i, asm in enumerate(blocks):
        lines += [f"# LLVM-MCA-BEGIN b{i}", *map(_llvm_syntax, asm), "# LLVM-MCA-END"]
    cmd = [find_llvm_mca(), *MCA_ARGS, "-"]
    run = subprocess.run(cmd, input="\n".join(lines) + "\n", capture_output=True, text=True)
    # An instruction llvm-mc rejects is reported on stderr and dropped, with exit status 0.
    err = next((ln for ln in run.stderr.splitlines() if "error:" in ln), None)
    if run.returncode != 0 or err:
        m = re.match(r"<stdin>:(\d+):", err or "")
        where = f" ({lines[int(m.group(1)) - 1]!r})" if m else ""
        raise ToolError(f"llvm-mca: {err or run.stderr.strip()}{where}")
    # One summary per region, in order; its instruction count proves nothing was dropped.
    found = [(int(n), int(t)) for n, t in _SUMMARY.findall(run.stdout)]
    if [n for n, _t in found] != [len(asm) for asm in blocks]:
        raise ToolError(f"llvm-mca: the summaries do not match the {len(blocks)} blocks given")
    totals = [t for _n, t in found]
    # "Total Cycles" runs from the cycle the first instruction is dispatched to the one the last
    # retires, inclusive; an instruction of latency L dispatched at cycle c writes back at c + L,
    # so a lone ADD is 2 and a lone VDIV 15. One cycle less is the block's own length in the
    # model's convention (an ADD 1, a VDIV 14). -iterations=1 runs the block once: no overlap
    # with a next iteration, a single pass start to retirement.
    return [t - 1 for t in totals]


def block_cycles(asm: list[str]) -> int:
    """Cycles of one pass through a block of GNU-syntax instructions (as the decoder prints them)."""
    return blocks_cycles([asm])[0]


def _texts(an, b) -> list[str]:
    """The block re-disassembled in one Capstone pass: the decoder decodes one instruction at a
    time, so an instruction inside an IT block comes without its condition (`vneg.f32` for
    `vneglt.f32`), which llvm-mc rejects ("incorrect condition in IT block"). One pass carries
    the IT state."""
    code = an.image.read(b.addr, b.end - b.addr)
    out = [(i.address, f"{i.mnemonic} {i.op_str}".strip()) for i in an.dec.cs.disasm(code, b.addr)]
    if [a for a, _t in out] != [i.addr for i in b.insns]:
        raise ToolError(f"block 0x{b.addr:08x}: re-disassembly disagrees with the decoder")
    return [t for _a, t in out]


def cross_check(elf_path: Path, sources_dir: Path, entry: str) -> list[dict]:
    """{function, addr, n_insns, mca, lenient, strict, strict_cheaper} for every static block of
    `entry` and its callees. The model's block cost charges IT-conditional instructions as executed (llvm-mca
    ignores predicates: the same) and the final branch not taken (llvm-mca has no taken-branch
    penalty: the same), so the two measure the same straight-line pass."""
    an = Analysis(Image(Path(elf_path)), Path(sources_dir))
    rows, asm, seen, work = [], [], set(), [entry]
    while work:
        fn = work.pop()
        if fn in seen:
            continue
        seen.add(fn)
        for addr, b in sorted(an.graph(fn).items()):
            # The strict table is not the lenient one plus stalls: it also charges VMOV core<->S
            # and a single-register STR/VSTR 1 where the lenient one charges 2, so a block may
            # cost less under it; lenient <= strict + strict_cheaper always holds.
            cheaper = sum(max(i.cost.cycles - i.cost.strict, 0) for i in b.insns)
            rows.append(dict(function=fn, addr=addr, n_insns=len(b.insns), mca=None,
                             lenient=b.cost["lenient"], strict=b.cost["strict"], strict_cheaper=cheaper))
            asm.append(_texts(an, b))
            if b.call:
                work.append(b.call)
    for row, cycles in zip(rows, blocks_cycles(asm)):
        row["mca"] = cycles
    return rows
