"""STM32F417 build (PIL): generated C + adapter + startup + harness -> ELF, and its evaluation.

Every C file is compiled with exactly firmware.flags.COMMON + ARM_CPU (the SPEC section 5 flags,
optimisation level replaceable for benchmarks) plus -fstack-usage and per-function/data
sections; the link uses stm32f417.ld, no start files, no C library unless an object needs one
(then newlib-nano's libc, recorded in the build), libgcc, --gc-sections and a map file. After
linking, `arm-none-eabi-nm` must show no libm function and no HAL symbol.

Builds are cached like the x86 ones: $STAREGEN_CACHE/arm/<sha256 of inputs>.
"""
from __future__ import annotations

import hashlib
import json
import os
import re
import shutil
import subprocess
import tempfile
from dataclasses import dataclass
from pathlib import Path
from typing import Mapping, Sequence

import jinja2

from firmware import symbols
from firmware.cache import discard, file_sha256
from firmware.errors import FirmwareError
from firmware.flags import ARM_CC, ARM_CPU, COMMON, with_opt

HERE = Path(__file__).resolve().parent
LINKER_SCRIPT = HERE / "stm32f417.ld"
SUPPORT_FILES = ("startup.c", "harness.c", "harness.h")
ADAPTERS = HERE / "adapters"
BENCH = HERE / "bench"
ARM_NM = "arm-none-eabi-nm"
ARM_SIZE = "arm-none-eabi-size"
EXTRA_CFLAGS = ["-g", "-fstack-usage", "-ffunction-sections", "-fdata-sections"]
BUILD_LAYOUT = "3"   # 2: the manifest holds the ELF sha256, checked before use; 3: -g (line table for loop bounds)

# Names that would mean libm (or a vendor HAL) got linked in.
_LIBM, _HAL = symbols.LIBM, symbols.HAL


@dataclass(frozen=True)
class ArmBuild:
    folder: Path
    elf: Path
    map: Path
    newlib: bool   # True when newlib-nano's libc had to be linked (an object called memcpy etc.)

    @property
    def su_files(self) -> list[Path]:
        return sorted((self.folder / "obj").glob("*.su"))


def tool(name: str) -> str:
    """Path of an ARM toolchain program; FirmwareError (one line) when it is missing."""
    path = shutil.which(name)
    if path is None:
        raise FirmwareError(f"ARM toolchain: '{name}' not found on PATH "
                            "(install gcc-arm-none-eabi and libnewlib-arm-none-eabi, see tools/setup.sh)")
    return path


def cflags(opt: str = "-O2", peer: bool = False) -> list[str]:
    """The flight flags; a peer build (third-party C measured for comparison, e.g. emlearn)
    keeps them all but -Werror, since its headers are not written for -Wextra -pedantic."""
    flags = [*with_opt(COMMON, opt), *ARM_CPU, *EXTRA_CFLAGS]
    return [f for f in flags if f != "-Werror"] if peer else flags


def compiler_version() -> str:
    out = subprocess.run([tool(ARM_CC), "--version"], capture_output=True, text=True, check=False)
    return out.stdout.splitlines()[0] if out.stdout else ARM_CC


def render_adapter(kind: str, **params) -> str:
    """C text of firmware/adapters/<kind>.c.j2 (records: entry, header, step, layout_checks, input_words,
    output_words, state_words (0: stateless); sequence: the same plus init)."""
    path = ADAPTERS / f"{kind}.c.j2"
    if not path.is_file():
        known = ", ".join(sorted(p.name[:-5] for p in ADAPTERS.glob("*.c.j2")))
        raise FirmwareError(f"no harness adapter '{kind}' (known: {known})")
    env = jinja2.Environment(undefined=jinja2.StrictUndefined, keep_trailing_newline=True, trim_blocks=True,
                             lstrip_blocks=True)
    try:
        return env.from_string(path.read_text(encoding="utf-8")).render(**params)
    except jinja2.UndefinedError as exc:
        raise FirmwareError(f"adapter '{kind}': {exc}") from None


def _one_line(text: str) -> str:
    lines = [ln.strip() for ln in text.splitlines() if ln.strip()]
    errors = [ln for ln in lines if "error" in ln or "undefined reference" in ln]
    return (errors or lines or ["(no output)"])[0]


def _run(cmd: Sequence[str], what: str) -> subprocess.CompletedProcess:
    try:
        return subprocess.run(list(cmd), capture_output=True, text=True, check=False)
    except FileNotFoundError:
        raise FirmwareError(f"ARM toolchain: '{cmd[0]}' not found ({what})") from None


def _compile(src: Path, obj_dir: Path, opt: str, peer: bool) -> list[Path]:
    cc = tool(ARM_CC)
    objects = []
    for c_file in sorted(src.glob("*.c")):
        obj = obj_dir / (c_file.stem + ".o")
        # The line table names the sources relative to the build folder, so a rebuild in another
        # temporary folder gives the same bytes (the cached ELF is checked against its hash).
        res = _run([cc, *cflags(opt, peer), f"-fdebug-prefix-map={src.parent}=.", "-I", str(src), "-c",
                    str(c_file), "-o", str(obj)], "compile")
        if res.returncode != 0:
            raise FirmwareError(f"ARM build: {c_file.name} does not compile: {_one_line(res.stderr)}")
        objects.append(obj)
    return objects


TABLE_PLACES = ("ccm", "flash")


def linker_script(tables: str = "ccm") -> str:
    """The STM32F417 linker script with the constant tables in CCM (copied at start-up) or, for
    tables larger than CCM, left in flash."""
    if tables not in TABLE_PLACES:
        raise FirmwareError(f"constant tables go to one of {', '.join(TABLE_PLACES)}, not {tables!r}")
    text = LINKER_SCRIPT.read_text()
    return text if tables == "ccm" else text.replace("} > CCM AT > FLASH", "} > FLASH")


def _link(objects: list[Path], elf: Path, map_file: Path, libs: list[str]) -> subprocess.CompletedProcess:
    script = elf.parent / "link.ld"
    cmd = [tool(ARM_CC), *ARM_CPU, "-nostartfiles", "-nostdlib", "-T", str(script),
           "-Wl,--gc-sections", f"-Wl,-Map={map_file}", "-o", str(elf), *map(str, objects), *libs]
    return _run(cmd, "link")


def link(objects: list[Path], elf: Path, map_file: Path) -> bool:
    """Link without any C library; only if that leaves undefined references, add newlib-nano's
    libc. Returns whether newlib was needed."""
    res = _link(objects, elf, map_file, ["-lgcc"])
    if res.returncode == 0:
        return False
    if "undefined reference" in res.stderr:
        res = _link(objects, elf, map_file, ["-lc_nano", "-lgcc"])
        if res.returncode == 0:
            return True
    raise FirmwareError(f"ARM build: link failed: {_link_problem(res.stderr)}")


_OVERFLOW = re.compile(r"region [`'](\w+)' overflowed by (\d+) bytes")
_REGION_KB = {"FLASH": 1024, "SRAM": 128, "CCM": 64}


def _link_problem(stderr: str) -> str:
    """The linker's complaint in one line; a memory overflow names the region and the sizes."""
    m = _OVERFLOW.search(stderr)
    if m:
        region, over = m.group(1), int(m.group(2))
        size = _REGION_KB.get(region)
        total = f" ({size} KB on the STM32F417, the image needs {size * 1024 + over} B)" if size else ""
        return f"the image does not fit {region}: overflowed by {over} B{total}"
    return _one_line(stderr)


def check_symbols(elf: Path, allow_libm: bool = False) -> None:
    """No libm function (unless allowed) and no HAL symbol in the image (arm-none-eabi-nm)."""
    res = _run([tool(ARM_NM), "--defined-only", str(elf)], "nm")
    if res.returncode != 0:
        raise FirmwareError(f"ARM build: nm failed on {elf.name}: {_one_line(res.stderr)}")
    names = [ln.split()[-1] for ln in res.stdout.splitlines() if ln.strip()]
    bad = sorted({n for n in names if (_LIBM.match(n) and not allow_libm) or _HAL.match(n)})
    if bad:
        raise FirmwareError(f"ARM build: forbidden library symbols linked: {', '.join(bad[:5])}")


def _build_into(folder: Path, files: Mapping[str, str], opt: str, peer: bool, tables: str) -> bool:
    src, obj = folder / "src", folder / "obj"
    src.mkdir(parents=True)
    obj.mkdir()
    (folder / "link.ld").write_text(linker_script(tables))
    for fname, text in files.items():
        (src / fname).write_text(text, encoding="utf-8")
    objects = _compile(src, obj, opt, peer)
    if peer:  # third-party C calls libm (tanhf, expf) and newlib
        res = _link(objects, folder / "firmware.elf", folder / "firmware.map", ["-lm", "-lc_nano", "-lgcc"])
        if res.returncode != 0:
            raise FirmwareError(f"ARM build: link failed: {_link_problem(res.stderr)}")
        newlib = True
    else:
        newlib = link(objects, folder / "firmware.elf", folder / "firmware.map")
    check_symbols(folder / "firmware.elf", allow_libm=peer)
    manifest = {"flags": cflags(opt, peer), "cc": compiler_version(), "newlib": newlib, "peer": peer,
                "files": sorted(files), "elf_sha256": file_sha256(folder / "firmware.elf")}
    (folder / "manifest.json").write_text(json.dumps(manifest, indent=2) + "\n")
    return newlib


def _cache_root() -> Path:
    env = os.environ.get("STAREGEN_CACHE")
    return (Path(env).expanduser() if env else Path.home() / ".cache" / "staregen") / "arm"


def _intact(folder: Path) -> bool:
    try:
        manifest = json.loads((folder / "manifest.json").read_text())
        return file_sha256(folder / "firmware.elf") == manifest["elf_sha256"]
    except (OSError, ValueError, KeyError, TypeError):
        return False


def build(sources: Mapping[str, str], adapter: str, opt: str = "-O2", peer: bool = False,
          tables: str = "ccm") -> ArmBuild:
    """Build (or fetch from the cache) the ELF of generated sources + an adapter's C text.

    peer=True is for benchmarks of third-party C only: libm and newlib are linked and
    warnings are not errors (see cflags). tables: where the constant tables run (linker_script)."""
    files = dict(sources)
    files["adapter.c"] = adapter
    for fname in SUPPORT_FILES:
        files[fname] = (HERE / fname).read_text(encoding="utf-8")
    key_parts = {"layout": BUILD_LAYOUT, "flags": cflags(opt, peer), "peer": peer, "cc": compiler_version(),
                 "ld": linker_script(tables), "files": sorted(files.items())}
    key = hashlib.sha256(json.dumps(key_parts, sort_keys=True).encode()).hexdigest()
    folder = _cache_root() / key
    if folder.is_dir() and not _intact(folder):
        discard(folder)   # a truncated or edited ELF must not be emulated or measured
    if not (folder / "manifest.json").is_file():
        folder.parent.mkdir(parents=True, exist_ok=True)
        tmp = Path(tempfile.mkdtemp(prefix=f".{key[:12]}.", suffix=".tmp", dir=folder.parent))
        try:
            _build_into(tmp, files, opt, peer, tables)
            try:
                os.rename(tmp, folder)
            except OSError:
                if not (folder / "manifest.json").is_file():
                    raise
        finally:
            shutil.rmtree(tmp, ignore_errors=True)
    newlib = json.loads((folder / "manifest.json").read_text())["newlib"]
    return ArmBuild(folder, folder / "firmware.elf", folder / "firmware.map", newlib)


def bench_build(out_dir: Path, sources: list[Path] | None = None) -> Path:
    """Assemble the micro-benchmarks (firmware/bench/*.S, or the given assembly files) into one
    ELF in out_dir."""
    out_dir.mkdir(parents=True, exist_ok=True)
    elf = out_dir / "bench.elf"
    sources = sorted(str(p) for p in (BENCH.glob("*.S") if sources is None else sources))
    cmd = [tool(ARM_CC), *ARM_CPU, "-g", "-I", str(BENCH), "-nostartfiles", "-nostdlib",
           "-T", str(LINKER_SCRIPT), "-Wl,-e,0", "-o", str(elf), *sources]
    res = _run(cmd, "assemble")
    if res.returncode != 0:
        raise FirmwareError(f"bench build failed: {_one_line(res.stderr)}")
    return elf
