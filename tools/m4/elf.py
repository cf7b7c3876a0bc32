"""A linked Cortex-M ELF as the emulator needs it: load segments, symbols, functions, code bytes."""
from __future__ import annotations

import bisect
import struct
from dataclasses import dataclass
from pathlib import Path

from elftools.common.exceptions import ELFError
from elftools.elf.elffile import ELFFile

from tools.errors import ToolError

EM_ARM = "EM_ARM"


@dataclass(frozen=True)
class Function:
    name: str
    start: int   # address without the Thumb bit
    size: int


@dataclass(frozen=True)
class Segment:
    addr: int    # load (physical) address: .data's and the tables' images sit in flash, startup copies them
    data: bytes
    vaddr: int = -1  # run address (differs from addr for what startup copies to RAM)


class Image:
    """Everything read from the ELF file once; the file is not kept open."""

    def __init__(self, path: str | Path):
        self.path = Path(path)
        try:
            with open(self.path, "rb") as fh:
                elf = ELFFile(fh)
                if elf["e_machine"] != EM_ARM:
                    raise ToolError(f"{self.path}: not an ARM ELF (machine {elf['e_machine']})")
                self.segments = [Segment(s["p_paddr"], s.data(), s["p_vaddr"]) for s in elf.iter_segments()
                                 if s["p_type"] == "PT_LOAD" and s["p_filesz"] > 0]
                self.symbols, funcs, self.objects = _read_symbols(elf)
                self.mapping = _read_mapping_symbols(elf)
                self.sections = {s.name: (s["sh_addr"], s["sh_size"], s["sh_flags"], s["sh_type"])
                                 for s in elf.iter_sections() if s.name}
        except OSError as exc:
            raise ToolError(f"cannot read ELF {self.path}: {exc.strerror or exc}") from None
        except (ELFError, struct.error, ValueError, KeyError) as exc:
            raise ToolError(f"corrupt ELF {self.path}: {exc}") from None
        if not self.segments:
            raise ToolError(f"corrupt ELF {self.path}: no loadable segment")
        self.functions = sorted(funcs, key=lambda f: f.start)
        self._starts = [f.start for f in self.functions]
        self.by_name = {f.name: f for f in self.functions}

    def symbol(self, name: str) -> int:
        """Address of a symbol (Thumb bit cleared for functions)."""
        if name in self.by_name:
            return self.by_name[name].start
        if name not in self.symbols:
            raise ToolError(f"symbol '{name}' is not in {self.path.name}")
        return self.symbols[name]

    def function(self, name: str) -> Function:
        if name not in self.by_name:
            raise ToolError(f"function '{name}' is not in {self.path.name}")
        return self.by_name[name]

    def function_index(self, addr: int) -> int:
        """Index into self.functions of the function containing addr, or -1."""
        i = bisect.bisect_right(self._starts, addr) - 1
        if i >= 0 and addr < self.functions[i].start + max(self.functions[i].size, 2):
            return i
        return -1

    def flash_objects(self, flash: tuple[int, int]) -> list[Function]:
        """Data objects the image keeps in flash (tables left there), the vector table aside."""
        lo, hi = flash[0], flash[0] + flash[1]
        vec = self.sections.get(".isr_vector", (0, 0, 0, 0))
        return [o for o in self.objects if lo <= o.start < hi and not vec[0] <= o.start < vec[0] + vec[1]]

    def read(self, addr: int, size: int) -> bytes:
        """Bytes of the loaded image at addr: a load address (flash), else a run address whose
        initial value the image holds (a constant startup copies to RAM, e.g. adapter_in_bytes)."""
        for base in ("addr", "vaddr"):
            for seg in self.segments:
                a = getattr(seg, base)
                if a <= addr and addr + size <= a + len(seg.data):
                    off = addr - a
                    return seg.data[off:off + size]
        raise ToolError(f"{self.path.name}: address 0x{addr:08x} is not in a loaded segment")

    def code_ranges(self, start: int, size: int) -> list[tuple[int, int]]:
        """The (addr, size) pieces of [start, start+size) that hold instructions, not data.

        ARM ELF mapping symbols mark where code ($t, Thumb) and data ($d: literal pools, jump
        tables) begin; decoding a literal pool as Thumb gives invented branches.
        """
        end = start + size
        marks = [(a, k) for a, k in self.mapping if start < a < end]
        before = [k for a, k in self.mapping if a <= start]
        kind = before[-1] if before else "t"
        pieces, cursor = [], start
        for addr, k in marks + [(end, None)]:
            if kind == "t" and addr > cursor:
                pieces.append((cursor, addr - cursor))
            cursor, kind = addr, k
        return pieces

    def word(self, name: str) -> int:
        """A 32-bit constant stored in the image (e.g. adapter_in_bytes)."""
        return struct.unpack("<I", self.read(self.symbol(name), 4))[0]


def _read_symbols(elf) -> tuple[dict[str, int], list[Function], list[Function]]:
    """Symbols by name, functions, and data objects (STT_OBJECT with a size, as Function records)."""
    symtab = elf.get_section_by_name(".symtab")
    if symtab is None:
        raise ToolError("ELF has no symbol table (stripped?)")
    symbols: dict[str, int] = {}
    funcs: dict[int, Function] = {}
    objects: list[Function] = []
    for s in symtab.iter_symbols():
        if not s.name or s["st_shndx"] == "SHN_UNDEF":
            continue
        kind = s["st_info"]["type"]
        value = s["st_value"]
        if kind == "STT_FUNC":
            value &= ~1
            # One name per address: the first seen, unless it had no size and this one is global.
            prev = funcs.get(value)
            if prev is None or (s["st_info"]["bind"] == "STB_GLOBAL" and prev.size == 0):
                funcs[value] = Function(s.name, value, s["st_size"])
        elif kind == "STT_OBJECT" and s["st_size"]:
            objects.append(Function(s.name, value, s["st_size"]))
        symbols.setdefault(s.name, value)
    return symbols, list(funcs.values()), objects


def _read_mapping_symbols(elf) -> list[tuple[int, str]]:
    """Sorted (address, 't' | 'd' | 'a') from the ARM mapping symbols $t, $d, $a (and $t.N, ...)."""
    marks = []
    for s in elf.get_section_by_name(".symtab").iter_symbols():
        name = s.name
        if name[:2] in ("$t", "$d", "$a") and (len(name) == 2 or name[2] == "."):
            marks.append((s["st_value"] & ~1, name[1]))
    return sorted(set(marks))
