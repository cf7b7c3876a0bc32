"""A flight package linked into this process as a firmware team links it: the package's own
sources, called through its public API (`<entry>_init`, `<entry>_step` on the ICD's records), on
x86-64 with the flight flags (cffi). Another simulator (Basilisk) flies these entries.

Order, as on board: the folder is checked against its manifest first (`package check`: seal,
file hashes, no extra files); a folder that fails is never compiled or loaded. The bytes that
were checked (a private copy, not the folder) are compiled; then `<name>_selftest()` runs once,
and a package whose self-test reports a mismatch is refused (the README's "refuse to fly").
Record layouts are the caller's (the numpy dtypes of the unit's records); each is checked
against the C struct's size before a step is taken.
"""
from __future__ import annotations

import tempfile
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from codegen import units as unit_registry
from codegen.names import NAME, identifier_problem
from codegen.package import manifest
from firmware import x86
from firmware.errors import FirmwareError
from tools.errors import ToolError

_SIZE_WHAT = ("state", "input", "output")


@dataclass(frozen=True)
class Records:
    """The numpy dtypes of one unit's records (state None for a stateless unit)."""

    input: np.dtype
    output: np.dtype
    state: np.dtype | None


def _entries(doc: dict) -> dict[str, str]:
    """{unit kind: entry prefix} of a checked manifest, each name checked before it reaches C."""
    units = doc.get("units")
    if not isinstance(units, dict) or not units:
        raise ToolError("package: the manifest lists no units")
    known = unit_registry.kinds()
    out = {}
    for kind, info in units.items():
        entry = info.get("entry") if isinstance(info, dict) else None
        if kind not in known:
            raise ToolError(f"package: unit {kind!r} is not a unit this staregen knows")
        if not isinstance(entry, str) or identifier_problem(entry) is not None:
            raise ToolError(f"package: unit {kind}: entry name {entry!r} is not a C identifier staregen writes")
        out[kind] = entry
    return out


def _read_sources(folder: Path) -> dict[str, str]:
    """The package's headers and C files (include/, src/, selftest/) as one flat name -> text map."""
    sources: dict[str, str] = {}
    for sub in ("include", "src", "selftest"):
        for path in sorted((folder / sub).glob("*.[ch]")):
            if path.name in sources:
                raise ToolError(f"package: {path.name} appears twice ({sub}/ and another folder)")
            try:
                sources[path.name] = path.read_text(encoding="utf-8")
            except UnicodeDecodeError:
                raise ToolError(f"package: {sub}/{path.name} is not UTF-8 text") from None
    return sources


def _stateful(headers: dict[str, str], entry: str) -> bool:
    return any(f"void {entry}_init(" in text for text in headers.values())


def _harness(name: str, entries: dict[str, str], stateful: dict[str, bool]) -> tuple[str, str]:
    """(cdef, harness): void-pointer wrappers of each entry's public API and its struct sizes."""
    cdef = ["int sg_pkg_selftest(void);"]
    c = ["#include <stddef.h>", f'#include "{name}_selftest.h"']
    c += [f'#include "{entry}.h"' for entry in entries.values()]
    c += ["", f"static int sg_pkg_selftest(void) {{ return (int){name}_selftest(); }}"]
    for kind, e in entries.items():
        cdef += [f"void sg_pkg_{kind}_init(void *state);",
                 f"void sg_pkg_{kind}_step(void *state, const void *in, void *out);",
                 f"size_t sg_pkg_{kind}_size(int which);"]
        if stateful[kind]:
            init = f"{e}_init(({e}_state_t *)state);"
            step = f"{e}_step(({e}_state_t *)state, (const {e}_input_t *)in, ({e}_output_t *)out);"
            state_size = f"sizeof({e}_state_t)"
        else:
            init = "(void)state;"
            step = f"(void)state; {e}_step((const {e}_input_t *)in, ({e}_output_t *)out);"
            state_size = "(size_t)0"
        c += [f"static void sg_pkg_{kind}_init(void *state) {{ {init} }}",
              f"static void sg_pkg_{kind}_step(void *state, const void *in, void *out) {{ {step} }}",
              f"static size_t sg_pkg_{kind}_size(int which) {{ return which == 0 ? {state_size} : "
              f"which == 1 ? sizeof({e}_input_t) : sizeof({e}_output_t); }}"]
    return "\n".join(cdef) + "\n", "\n".join(c) + "\n"


class PackageEntry:
    """One unit of a loaded package: init once, then one step per control period."""

    def __init__(self, package: "FlightPackage", kind: str, records: Records):
        self.package, self.kind, self.records = package, kind, records
        lib = package.build.lib
        self._init, self._step = getattr(lib, f"sg_pkg_{kind}_init"), getattr(lib, f"sg_pkg_{kind}_step")
        sizes = [int(getattr(lib, f"sg_pkg_{kind}_size")(i)) for i in range(3)]
        want = [0 if records.state is None else records.state.itemsize, records.input.itemsize,
                records.output.itemsize]
        for what, got, expected in zip(_SIZE_WHAT, sizes, want):
            if got != expected:
                raise ToolError(f"package {package.name}: unit {kind}: the C {what} record is {got} bytes, "
                                f"this staregen's is {expected}")
        self.state = np.zeros(1, records.state) if records.state is not None else np.zeros(1, np.uint32)
        self.init()

    def _ptr(self, a: np.ndarray):
        ffi = self.package.build.ffi
        return ffi.cast("void *", ffi.from_buffer(a))

    def init(self) -> None:
        self._init(self._ptr(self.state))

    def step(self, record: np.ndarray) -> np.ndarray:
        """The unit's output record of one input record (its state carried in this object)."""
        inp = np.ascontiguousarray(record, dtype=self.records.input).reshape(1)
        out = np.zeros(1, dtype=self.records.output)
        self.package.build.check_fp_environment()
        self._step(self._ptr(self.state), self._ptr(inp), self._ptr(out))
        return out


class FlightPackage:
    """A checked package compiled and self-tested; `entry(kind, records)` gives one unit's API."""

    def __init__(self, name: str, entries: dict[str, str], build: x86.X86Build, manifest_doc: dict):
        self.name, self.entries, self.build, self.manifest = name, entries, build, manifest_doc

    def entry(self, kind: str, records: Records) -> PackageEntry:
        if kind not in self.entries:
            raise ToolError(f"package {self.name} holds no {kind} unit (it holds: {', '.join(self.entries)})")
        return PackageEntry(self, kind, records)


def load_package(folder: str | Path, key: bytes | None = None) -> FlightPackage:
    """Check (with `key`: its HMAC-SHA256 signature too), compile and self-test the package in `folder`;
    ToolError (one line) if any step fails."""
    folder = Path(folder)
    if not folder.is_dir():
        raise ToolError(f"package {folder}: no such folder")
    doc, problems = manifest.check(folder, key)
    if problems:
        raise ToolError(f"package {folder} fails its check, not loaded: {problems[0]}")
    name = doc.get("name")
    if not isinstance(name, str) or not NAME.fullmatch(name):
        raise ToolError(f"package {folder}: package name {name!r} is not one staregen writes")
    entries = _entries(doc)
    with tempfile.TemporaryDirectory(prefix="staregen-load-") as tmp:
        problems = manifest.copy_verified(folder, doc, tmp)   # compile the bytes checked, not the folder
        if problems:
            raise ToolError(f"package {folder} changed while being checked, not loaded: {problems[0]}")
        sources = _read_sources(Path(tmp))
    stateful = {kind: _stateful(sources, e) for kind, e in entries.items()}
    cdef, harness = _harness(name, entries, stateful)
    try:
        build = x86.build(sources, cdef, harness)
    except FirmwareError as exc:
        raise ToolError(f"package {folder}: does not build on x86-64: {exc}") from None
    build.check_fp_environment()
    mismatches = int(build.lib.sg_pkg_selftest())
    if mismatches != 0:
        raise ToolError(f"package {folder}: its self-test reports {mismatches} mismatching words; refusing to fly it")
    return FlightPackage(name, entries, build, doc)
