"""x86-64 build (SIL): generated C compiled with the flight flags, wrapped by cffi (out-of-line API mode).

The flight sources are compiled by gcc with exactly firmware.flags.COMMON (+ -fPIC) into object
files; cffi's own wrapper (compiled with Python's flags) only links them and adds batch loops that
call the flight functions row by row. Builds land in a cache folder keyed by the sha256 of the
sources, cdef, harness, flags, compiler version and Python ABI:
    $STAREGEN_CACHE/x86/<hash>   (default ~/.cache/staregen/x86/<hash>)
A build happens in a temporary sibling folder that is renamed into place, so concurrent builds
of the same key are safe (the first rename wins; the loser's copy is discarded).
"""
from __future__ import annotations

import hashlib
import importlib.machinery
import importlib.util
import json
import os
import shutil
import subprocess
import sys
import sysconfig
import tempfile
from dataclasses import dataclass
from pathlib import Path
from types import ModuleType
from typing import Mapping

import cffi

from firmware import symbols
from firmware.cache import discard, file_sha256
from firmware.errors import FirmwareError
from firmware.flags import COMMON

X86_CC = "gcc"
X86_FLAGS = [*COMMON, "-fPIC"]
# Bump when the layout of a cache folder changes (2: every module carries the host helpers below;
# 3: the manifest holds the module's sha256, checked before loading).
BUILD_LAYOUT = "3"

# Host helpers appended to every cffi wrapper (never to the flight sources, which stay free of
# intrinsics): read the SSE control register so a batch can refuse to run when something else in
# this process set flush-to-zero, denormals-are-zero or a directed rounding mode (the golden model
# assumes IEEE defaults). The setter exists for the tests only.
HOST_CDEF = """
unsigned int sg_host_mxcsr(void);
void sg_host_set_mxcsr(unsigned int value);
"""
HOST_HARNESS = """
#include <xmmintrin.h>
static unsigned int sg_host_mxcsr(void) { return _mm_getcsr(); }
static void sg_host_set_mxcsr(unsigned int value) { _mm_setcsr(value); }
"""
MXCSR_DAZ = 1 << 6
MXCSR_FTZ = 1 << 15
MXCSR_RC = 3 << 13  # rounding control; 00 = round to nearest even
_ROUNDING = {1: "round-down", 2: "round-up", 3: "round-toward-zero"}

_loaded: dict[str, "X86Build"] = {}


@dataclass(frozen=True)
class X86Build:
    """A loaded build: the cffi ffi/lib, its cache folder and the flight object files."""

    key: str
    folder: Path
    ffi: object
    lib: object

    @property
    def objects(self) -> list[Path]:
        return sorted((self.folder / "obj").glob("*.o"))

    @property
    def sources(self) -> Path:
        return self.folder / "src"

    def check_fp_environment(self) -> None:
        """Raise FirmwareError if this thread's MXCSR is not the IEEE default the golden model
        assumes. MXCSR can be changed at any time by another library (e.g. one built with
        fast-math options), so batch entry points call this before each call into the flight code."""
        csr = int(self.lib.sg_host_mxcsr())
        bad = []
        if csr & MXCSR_FTZ:
            bad.append("flush-to-zero (FTZ)")
        if csr & MXCSR_DAZ:
            bad.append("denormals-are-zero (DAZ)")
        if csr & MXCSR_RC:
            bad.append(f"rounding mode {_ROUNDING[(csr & MXCSR_RC) >> 13]}")
        if bad:
            raise FirmwareError(
                f"x86 SIL: MXCSR 0x{csr:04x} has {', '.join(bad)} set: subnormal or rounded results would "
                "differ from the golden model; something in this process changed the SSE control register")


def cache_root() -> Path:
    """$STAREGEN_CACHE, else ~/.cache/staregen."""
    env = os.environ.get("STAREGEN_CACHE")
    return Path(env).expanduser() if env else Path.home() / ".cache" / "staregen"


def compiler_version(cc: str = X86_CC) -> str:
    if shutil.which(cc) is None:
        raise FirmwareError(f"x86 build: C compiler '{cc}' not found on PATH (install gcc)")
    out = subprocess.run([cc, "--version"], capture_output=True, text=True, check=False)
    return out.stdout.splitlines()[0] if out.stdout else cc


def build_key(sources: Mapping[str, str], cdef: str, harness: str, cc: str = X86_CC) -> str:
    h = hashlib.sha256()
    parts = {
        "layout": BUILD_LAYOUT, "flags": X86_FLAGS, "cc": compiler_version(cc),
        "abi": sysconfig.get_config_var("EXT_SUFFIX"), "python": sys.version.split()[0],
        "cffi": cffi.__version__, "cdef": cdef, "harness": harness, "host": HOST_CDEF + HOST_HARNESS,
        "sources": sorted(sources.items()),
    }
    h.update(json.dumps(parts, sort_keys=True).encode("utf-8"))
    return h.hexdigest()


def _module_name(key: str) -> str:
    return f"_sg_x86_{key[:24]}"


def _one_line(text: str) -> str:
    """The first compiler diagnostic (or the first non-empty line) of a build log."""
    lines = [ln.strip() for ln in text.splitlines() if ln.strip()]
    errors = [ln for ln in lines if "error" in ln]
    return (errors or lines or ["(no compiler output)"])[0]


def compile_objects(src_dir: Path, obj_dir: Path, cc: str = X86_CC) -> list[Path]:
    """Compile every .c of src_dir with the flight flags; a failure raises FirmwareError (one line)."""
    obj_dir.mkdir(parents=True, exist_ok=True)
    objects = []
    for c_file in sorted(src_dir.glob("*.c")):
        obj = obj_dir / (c_file.stem + ".o")
        cmd = [cc, *X86_FLAGS, "-I", str(src_dir), "-c", str(c_file), "-o", str(obj)]
        try:
            res = subprocess.run(cmd, capture_output=True, text=True, check=False)
        except FileNotFoundError:
            raise FirmwareError(f"x86 build: C compiler '{cc}' not found on PATH (install gcc)") from None
        if res.returncode != 0:
            raise FirmwareError(f"x86 build: {c_file.name} does not compile: {_one_line(res.stderr)}")
        objects.append(obj)
    check_undefined(objects)
    return objects


def check_undefined(objects: list[Path]) -> None:
    """Flight objects may reference no libm or allocation function: inside the Python process
    such a call would silently resolve to the host's libm (SPEC section 5)."""
    try:
        res = subprocess.run(["nm", "--undefined-only", *map(str, objects)], capture_output=True, text=True,
                             check=False)
    except FileNotFoundError:
        raise FirmwareError("x86 build: 'nm' (binutils) not found on PATH") from None
    names = {ln.split()[-1] for ln in res.stdout.splitlines() if ln.strip() and not ln.endswith(":")}
    bad = sorted(n for n in names if symbols.LIBM.match(n) or symbols.ALLOCATION.match(n))
    if bad:
        raise FirmwareError(f"x86 build: flight code references forbidden library symbols: {', '.join(bad[:5])}")


def _build_into(folder: Path, key: str, sources: Mapping[str, str], cdef: str, harness: str, cc: str) -> None:
    src = folder / "src"
    src.mkdir(parents=True)
    for fname, text in sources.items():
        (src / fname).write_text(text, encoding="utf-8")
    objects = compile_objects(src, folder / "obj", cc)
    ffi = cffi.FFI()
    ffi.cdef(cdef + HOST_CDEF)
    ffi.set_source(_module_name(key), harness + HOST_HARNESS, include_dirs=[str(src)],
                   extra_objects=[str(o) for o in objects])
    log = folder / "build.log"
    try:
        with open(log, "w") as fh, _redirect_fds(fh):
            built = Path(ffi.compile(tmpdir=str(folder / "wrap"), verbose=False))
    except Exception as exc:  # cffi raises VerificationError/CompileError/LinkError
        raise FirmwareError(f"x86 build: cffi wrapper failed: {_one_line(str(exc) or log.read_text())}") from None
    built.rename(folder / built.name)
    manifest = {"key": key, "flags": X86_FLAGS, "cc": compiler_version(cc), "files": sorted(sources),
                "module": built.name, "module_sha256": file_sha256(folder / built.name)}
    (folder / "manifest.json").write_text(json.dumps(manifest, indent=2) + "\n")


class _redirect_fds:
    """Send the C compiler's stdout/stderr (file descriptors 1 and 2) to a log file while cffi builds."""

    def __init__(self, fh):
        self.fh = fh

    def __enter__(self):
        sys.stdout.flush()
        sys.stderr.flush()
        self.saved = (os.dup(1), os.dup(2))
        os.dup2(self.fh.fileno(), 1)
        os.dup2(self.fh.fileno(), 2)

    def __exit__(self, *exc):
        sys.stdout.flush()
        sys.stderr.flush()
        os.dup2(self.saved[0], 1)
        os.dup2(self.saved[1], 2)
        os.close(self.saved[0])
        os.close(self.saved[1])
        return False


def cache_entry_intact(folder: Path) -> bool:
    """The cached module is the one that was built: its sha256 matches the folder's manifest."""
    try:
        manifest = json.loads((folder / "manifest.json").read_text())
        return file_sha256(folder / manifest["module"]) == manifest["module_sha256"]
    except (OSError, ValueError, KeyError, TypeError):
        return False


def _load(folder: Path, key: str) -> X86Build:
    name = _module_name(key)
    paths = list(folder.glob(name + "*" + sysconfig.get_config_var("EXT_SUFFIX")))
    if len(paths) != 1:
        raise FirmwareError(f"x86 build: cache folder {folder} is incomplete (delete it to rebuild)")
    loader = importlib.machinery.ExtensionFileLoader(name, str(paths[0]))
    spec = importlib.util.spec_from_file_location(name, str(paths[0]), loader=loader)
    module: ModuleType = importlib.util.module_from_spec(spec)
    loader.exec_module(module)
    return X86Build(key=key, folder=folder, ffi=module.ffi, lib=module.lib)


def build(sources: Mapping[str, str], cdef: str, harness: str, cc: str = X86_CC) -> X86Build:
    """Compile (or fetch from the cache) and load a cffi module of the given C sources.

    sources: {file name: text} (headers and .c files, flight code); cdef: the declarations
    exposed to Python; harness: extra C placed in the cffi wrapper (includes, batch loops).
    HOST_CDEF / HOST_HARNESS are appended to both (see X86Build.check_fp_environment).
    """
    key = build_key(sources, cdef, harness, cc)
    if key in _loaded:
        return _loaded[key]
    parent = cache_root() / "x86"
    folder = parent / key
    if folder.is_dir() and not cache_entry_intact(folder):
        discard(folder)   # truncated or edited module: loading it could crash the process (SIGBUS)
    if not folder.is_dir():
        parent.mkdir(parents=True, exist_ok=True)
        tmp = Path(tempfile.mkdtemp(prefix=f".{key[:12]}.", suffix=".tmp", dir=parent))
        try:
            _build_into(tmp, key, sources, cdef, harness, cc)
            try:
                os.rename(tmp, folder)
            except OSError:
                if not folder.is_dir():  # a real failure, not a lost race
                    raise
        finally:
            shutil.rmtree(tmp, ignore_errors=True)
    _loaded[key] = _load(folder, key)
    return _loaded[key]
