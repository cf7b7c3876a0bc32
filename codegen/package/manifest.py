"""The flight package's manifest.json: the sha256 of every file, the inputs, the build and the
evidence, sealed by the sha256 of its own canonical text; and the check of a package folder
against it (edited, missing and extra files, each named on one line).

The manifest holds no date and no path of the generating machine, so generating twice from the
same inputs gives byte-identical packages.
"""
from __future__ import annotations

import hashlib
import json
import os
import re
import stat
from pathlib import Path

from codegen.errors import CodegenError
from codegen.package.config import NAME_PATTERN as NAME

FORMAT = "staregen.flight-package"
VERSION = 1
MANIFEST = "manifest.json"
# Every path a package may hold: nothing from a manifest is trusted to stay inside the folder otherwise.
PACKAGE_PATH = re.compile(r"(?:(?:include|selftest)/[A-Za-z0-9_]+\.h|(?:src|selftest)/[A-Za-z0-9_]+\.c"
                          r"|CMakeLists\.txt|ICD\.md)")
MAX_MANIFEST_BYTES = 4 << 20
# A package file is C, CMake or Markdown: far below this (the largest, a self-test of 4,096 vectors,
# is a few MB). Nothing larger is read, whatever st_size claims: reads stop at the cap.
MAX_FILE_BYTES = 64 << 20
MAX_ENTRIES = 1_000          # a package holds about a dozen files; a huge tree is refused, not walked
_CHUNK = 1 << 20


class PackageError(CodegenError):
    """A package folder or manifest that does not check out (one line)."""


def sha256_bytes(data: bytes) -> str:
    return hashlib.sha256(data).hexdigest()


def _canonical(doc: dict) -> bytes:
    return json.dumps(doc, sort_keys=True, separators=(",", ":"), ensure_ascii=True).encode("ascii")


def seal_of(doc: dict) -> str:
    """sha256 of the canonical text of everything but the seal itself."""
    return sha256_bytes(_canonical({k: v for k, v in doc.items() if k != "sha256"}))


def document(files: dict[str, bytes], body: dict) -> dict:
    """The manifest of package `files` ({relative path: bytes}) with `body` (generator, inputs,
    build, evidence): format, version, body, the files' sha256, and the seal."""
    for path in files:
        if not PACKAGE_PATH.fullmatch(path):
            raise PackageError(f"package path {path!r} is not one a package may hold")
    doc = {"format": FORMAT, "version": VERSION, **body,
           "files": {p: sha256_bytes(files[p]) for p in sorted(files)}}
    doc["sha256"] = seal_of(doc)
    return doc


def to_text(doc: dict) -> str:
    return json.dumps(doc, indent=2, sort_keys=False, ensure_ascii=True) + "\n"


def load(folder: str | Path) -> dict:
    """The folder's manifest, validated (format, version, file list, seal); PackageError otherwise."""
    path = Path(folder) / MANIFEST
    try:
        raw = read_regular(path, MAX_MANIFEST_BYTES)
    except FileNotFoundError:
        raise PackageError(f"{path}: missing (not a flight package folder?)") from None
    except NotRegular:
        raise PackageError(f"{path}: not a regular file (refused unopened)") from None
    except OSError as exc:
        raise PackageError(f"{path}: cannot read ({exc.strerror or exc})") from None
    if raw is None:
        raise PackageError(f"{path}: larger than {MAX_MANIFEST_BYTES} bytes")
    try:
        doc = json.loads(raw.decode("utf-8"))
    except (UnicodeDecodeError, json.JSONDecodeError, RecursionError) as exc:
        raise PackageError(f"{path}: not valid JSON: {str(exc).splitlines()[0] if str(exc) else 'too deep'}") from None
    if not isinstance(doc, dict) or doc.get("format") != FORMAT:
        raise PackageError(f"{path}: format: expected \"{FORMAT}\"")
    version = doc.get("version")
    if not isinstance(version, int) or isinstance(version, bool) or version != VERSION:
        raise PackageError(f"{path}: version: unsupported {version!r} (this staregen reads {VERSION})")
    name = doc.get("name")
    if not isinstance(name, str) or not NAME.fullmatch(name):
        raise PackageError(f"{path}: name: not a package entry name")
    files = doc.get("files")
    if not isinstance(files, dict) or not files:
        raise PackageError(f"{path}: files: missing or empty")
    for rel, digest in files.items():
        if not isinstance(rel, str) or not PACKAGE_PATH.fullmatch(rel):
            raise PackageError(f"{path}: files: {str(rel)[:60]!r} is not a path a package may hold")
        if not isinstance(digest, str) or not re.fullmatch(r"[0-9a-f]{64}", digest):
            raise PackageError(f"{path}: files[{rel}]: not a sha256")
    if doc.get("sha256") != seal_of(doc):
        raise PackageError(f"{path}: sha256: the manifest was edited after it was sealed")
    return doc


class NotRegular(OSError):
    """The path is not a regular file (a FIFO, device, socket, symlink or folder): never opened."""


def _open_regular(path: Path):
    """A binary file object of regular file `path`; NotRegular for anything else.

    lstat first, so that a FIFO or device is refused without being opened (opening a FIFO blocks,
    a device may act); then open without following a link and without blocking, and fstat again
    (the entry may have been swapped in between)."""
    if not stat.S_ISREG(os.lstat(path).st_mode):
        raise NotRegular(f"{path}: not a regular file")
    fd = os.open(path, os.O_RDONLY | getattr(os, "O_NOFOLLOW", 0) | getattr(os, "O_NONBLOCK", 0))
    f = os.fdopen(fd, "rb")
    if not stat.S_ISREG(os.fstat(fd).st_mode):
        f.close()
        raise NotRegular(f"{path}: not a regular file")
    return f


def _read_capped(f, limit: int, sink) -> bool:
    """Feed open file `f` to `sink` in chunks; False (and nothing more read) once it is known to
    hold more than `limit` bytes. st_size decides first, so a huge or sparse file is not read at
    all; the count of bytes actually read decides after (a file may grow, st_size may lie)."""
    if os.fstat(f.fileno()).st_size > limit:
        return False
    total = 0
    while True:
        chunk = f.read(min(_CHUNK, limit + 1 - total))
        if not chunk:
            return True
        total += len(chunk)
        if total > limit:
            return False
        sink(chunk)


def read_regular(path: Path, limit: int) -> bytes | None:
    """The bytes of a regular file, or None when it holds more than `limit` bytes."""
    parts: list[bytes] = []
    with _open_regular(path) as f:
        ok = _read_capped(f, limit, parts.append)
    return b"".join(parts) if ok else None


def file_sha256(path: Path, limit: int = MAX_FILE_BYTES) -> str | None:
    """sha256 of a regular file read in chunks, or None when it holds more than `limit` bytes."""
    h = hashlib.sha256()
    with _open_regular(path) as f:
        ok = _read_capped(f, limit, h.update)
    return h.hexdigest() if ok else None


def _entries(folder: Path) -> tuple[set[str], list[str]]:
    """(regular files, everything else that is not a folder: FIFOs, devices, sockets, symlinks),
    as paths relative to `folder`, by lstat alone (nothing is opened or followed)."""
    files, odd, todo, seen = set(), [], [""], 0
    while todo:
        rel = todo.pop()
        with os.scandir(folder / rel if rel else folder) as it:
            for entry in it:
                seen += 1
                if seen > MAX_ENTRIES:
                    raise PackageError(f"{folder}: more than {MAX_ENTRIES} entries (not a flight package folder?)")
                path = f"{rel}{entry.name}"
                if entry.is_dir(follow_symlinks=False):
                    todo.append(path + "/")
                elif entry.is_file(follow_symlinks=False):
                    files.add(path)
                else:
                    odd.append(path)
    files.discard(MANIFEST)
    return files, sorted(odd)


def _file_problem(folder: Path, rel: str, digest: str) -> str | None:
    """The one-line problem of a listed regular file, or None when its sha256 matches."""
    try:
        got = file_sha256(folder / rel)
    except NotRegular:
        return f"not a regular file or folder: {rel}"
    except OSError as exc:
        return f"cannot read file: {rel} ({exc.strerror or exc})"
    if got is None:
        return f"edited file: {rel} (larger than {MAX_FILE_BYTES} bytes; not read)"
    return None if got == digest else f"edited file: {rel} (sha256 differs from the manifest)"


def check(folder: str | Path) -> tuple[dict, list[str]]:
    """(manifest, problems): one line per edited, missing or extra file and per entry that is
    neither a regular file nor a folder (refused unopened); [] when the folder is exactly what
    the manifest says."""
    folder = Path(folder)
    if not folder.is_dir():
        raise PackageError(f"{folder}: not a directory")
    doc = load(folder)
    listed = doc["files"]
    try:
        present, odd = _entries(folder)
    except OSError as exc:
        raise PackageError(f"{folder}: cannot list ({exc.strerror or exc})") from None
    problems = [f"not a regular file or folder: {rel}" for rel in odd]
    for rel in sorted(listed):
        if rel in odd:
            continue
        problem = f"missing file: {rel}" if rel not in present else _file_problem(folder, rel, listed[rel])
        if problem:
            problems.append(problem)
    problems += [f"extra file: {rel}" for rel in sorted(present - set(listed))]
    return doc, problems
