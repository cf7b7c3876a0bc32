"""Flash and RAM of an ARM build: whole image (arm-none-eabi-size) and per object file (map file).

Flash = code + constants + the flash image of .data; RAM = .data + .bss. The harness arena and
the stack are test-harness reservations, reported apart. The network path's share is what the
linker kept from the generated objects (after --gc-sections), read from the map file.
"""
from __future__ import annotations

import re
import subprocess
from dataclasses import dataclass, field
from pathlib import Path

from firmware.arm import ARM_SIZE, tool
from tools.errors import ToolError
from tools.m4.machine import CCM, FLASH, SRAM

_FLASH_SECTIONS = (".isr_vector", ".text", ".tables", ".ARM.exidx", ".data")
_RAM_SECTIONS = (".data", ".bss")   # plus .tables when it runs from CCM
_RESERVED = (".harness_arena",)
_MAP_ROW = re.compile(r"^\s(\.\S+)?\s+0x([0-9a-fA-F]+)\s+0x([0-9a-fA-F]+)\s+(\S+)$")


@dataclass
class Sizes:
    sections: dict[str, int]
    flash: int
    ram: int
    reserved: int
    per_object: dict[str, dict[str, int]] = field(default_factory=dict)  # obj -> {"flash", "ram"}

    def of_objects(self, names) -> dict[str, int]:
        rows = [self.per_object.get(n, {"flash": 0, "ram": 0}) for n in names]
        return {"flash": sum(r["flash"] for r in rows), "ram": sum(r["ram"] for r in rows)}


def section_sizes(elf: Path) -> dict[str, int]:
    """arm-none-eabi-size -A: {section: bytes}; ".tables@ram" also holds .tables' size when it
    runs from RAM (CCM)."""
    res = subprocess.run([tool(ARM_SIZE), "-A", str(elf)], capture_output=True, text=True, check=False)
    if res.returncode != 0:
        raise ToolError(f"arm-none-eabi-size failed on {elf}: {res.stderr.strip().splitlines()[:1]}")
    out = {}
    for line in res.stdout.splitlines():
        parts = line.split()
        if len(parts) == 3 and parts[0].startswith(".") and parts[1].isdigit():
            out[parts[0]] = int(parts[1])
            if parts[0] == ".tables" and not _in(int(parts[2]), FLASH):
                out[".tables@ram"] = int(parts[1])
    return out


def _in(addr: int, region: tuple[int, int]) -> bool:
    return region[0] <= addr < region[0] + region[1]


def map_objects(map_file: Path) -> dict[str, dict[str, int]]:
    """Bytes each object file contributes to flash and RAM, from a GNU ld map file."""
    try:
        text = map_file.read_text(errors="replace")
    except OSError as exc:
        raise ToolError(f"cannot read map file {map_file}: {exc.strerror}") from None
    start = text.find("Linker script and memory map")
    if start < 0:
        raise ToolError(f"{map_file}: not a GNU ld map file")
    out: dict[str, dict[str, int]] = {}
    pending = None
    for line in text[start:].splitlines():
        if re.match(r"^\s\.\S+$", line):
            pending = line.strip()
            continue
        m = _MAP_ROW.match(line)
        if not m:
            pending = None
            continue
        name = m.group(1) or pending
        pending = None
        addr, size, obj = int(m.group(2), 16), int(m.group(3), 16), Path(m.group(4)).name
        if not name or size == 0 or not obj.endswith((".o", ")")):
            continue
        row = out.setdefault(obj, {"flash": 0, "ram": 0})
        if _in(addr, FLASH):
            row["flash"] += size
        elif _in(addr, SRAM) or _in(addr, CCM):
            row["ram"] += size
            if name.startswith((".data", ".rodata", ".sg_tables")):
                row["flash"] += size  # its initial values are stored in flash (copied at start-up)
    return out


def sizes(elf: Path, map_file: Path | None = None) -> Sizes:
    sec = section_sizes(elf)
    flash = sum(sec.get(s, 0) for s in _FLASH_SECTIONS)
    ram = sum(sec.get(s, 0) for s in _RAM_SECTIONS) + sec.get(".tables@ram", 0)
    reserved = sum(sec.get(s, 0) for s in _RESERVED)
    per_object = map_objects(map_file) if map_file is not None else {}
    return Sizes(sec, flash, ram, reserved, per_object)
