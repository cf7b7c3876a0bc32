"""The flight package's manifest.json: the sha256 of every file, the inputs, the build and the
evidence, sealed by the sha256 of its own canonical text; and the check of a package folder
against it (edited, missing and extra files, each named on one line).

The manifest holds no date and no path of the generating machine, so generating twice from the
same inputs gives byte-identical packages.
"""
from __future__ import annotations

import hashlib
import json
import re
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
        raw = path.read_bytes()
    except FileNotFoundError:
        raise PackageError(f"{path}: missing (not a flight package folder?)") from None
    except OSError as exc:
        raise PackageError(f"{path}: cannot read ({exc.strerror or exc})") from None
    if len(raw) > MAX_MANIFEST_BYTES:
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


def _present(folder: Path) -> set[str]:
    out = set()
    for p in folder.rglob("*"):
        if p.is_file() or p.is_symlink():
            rel = p.relative_to(folder).as_posix()
            if rel != MANIFEST:
                out.add(rel)
    return out


def check(folder: str | Path) -> tuple[dict, list[str]]:
    """(manifest, problems): one line per edited, missing or extra file; [] when the folder is
    exactly what the manifest says."""
    folder = Path(folder)
    if not folder.is_dir():
        raise PackageError(f"{folder}: not a directory")
    doc = load(folder)
    listed = doc["files"]
    present = _present(folder)
    problems = []
    for rel in sorted(listed):
        path = folder / rel
        if rel not in present:
            problems.append(f"missing file: {rel}")
        elif path.is_symlink() or not path.is_file():
            problems.append(f"not a regular file: {rel}")
        elif sha256_bytes(path.read_bytes()) != listed[rel]:
            problems.append(f"edited file: {rel} (sha256 differs from the manifest)")
    problems += [f"extra file: {rel}" for rel in sorted(present - set(listed))]
    return doc, problems
