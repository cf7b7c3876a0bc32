"""The flight package's manifest.json: the sha256 of every file, the inputs, the build and the
evidence, sealed by the sha256 of its own canonical text; and the check of a package folder
against it (edited, missing and extra files, each named on one line).

The seal catches accidents (a truncated copy, a stray edit, a lost file), not tampering: anyone
who edits a file can recompute its sha256 and the seal. Against tampering the manifest can be
signed with HMAC-SHA256 under a key file the user keeps (`generate --sign-key FILE`), and the
signature checked with the same key (`package check --verify-key FILE`).

The manifest holds no date and no path of the generating machine, so generating twice from the
same inputs gives byte-identical packages.
"""
from __future__ import annotations

import hashlib
import hmac
import json
import os
import re
import stat
from pathlib import Path

from codegen.errors import CodegenError
from codegen.names import name_problem

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
SIGNATURE = "signature"
SIGNATURE_ALGORITHM = "HMAC-SHA256"
KEY_MIN_BYTES = 32           # RFC 2104: a key shorter than the hash's output weakens the MAC
KEY_MAX_BYTES = 1024


class PackageError(CodegenError):
    """A package folder or manifest that does not check out (one line)."""


def sha256_bytes(data: bytes) -> str:
    return hashlib.sha256(data).hexdigest()


def _canonical(doc: dict) -> bytes:
    return json.dumps(doc, sort_keys=True, separators=(",", ":"), ensure_ascii=True).encode("ascii")


def seal_of(doc: dict) -> str:
    """sha256 of the canonical text of everything but the seal itself (the signature included)."""
    return sha256_bytes(_canonical({k: v for k, v in doc.items() if k != "sha256"}))


def signature_of(doc: dict, key: bytes) -> str:
    """HMAC-SHA256 under `key` of the canonical text of everything but the seal and the signature."""
    body = _canonical({k: v for k, v in doc.items() if k not in ("sha256", SIGNATURE)})
    return hmac.new(key, body, hashlib.sha256).hexdigest()


def document(files: dict[str, bytes], body: dict, key: bytes | None = None) -> dict:
    """The manifest of package `files` ({relative path: bytes}) with `body` (generator, inputs,
    build, evidence): format, version, body, the files' sha256, the signature under `key` when
    one is given, and the seal."""
    for path in files:
        if not PACKAGE_PATH.fullmatch(path):
            raise PackageError(f"package path {path!r} is not one a package may hold")
    doc = {"format": FORMAT, "version": VERSION, **body,
           "files": {p: sha256_bytes(files[p]) for p in sorted(files)}}
    if key is not None:
        doc[SIGNATURE] = {"algorithm": SIGNATURE_ALGORITHM, "hmac": signature_of(doc, key)}
    doc["sha256"] = seal_of(doc)
    return doc


def signature_problem(doc: dict, key: bytes) -> str | None:
    """The one-line problem of the manifest's signature under `key`, or None when it verifies."""
    if SIGNATURE not in doc:
        return "signature: the manifest is not signed (generate the package with --sign-key)"
    if not hmac.compare_digest(doc[SIGNATURE]["hmac"], signature_of(doc, key)):
        return "signature: does not verify with this key (a file was edited and re-sealed, or another key signed it)"
    return None


def load_key(path: str | Path) -> bytes:
    """The bytes of a signing key file: a regular file of KEY_MIN_BYTES to KEY_MAX_BYTES (read no
    further), e.g. `head -c 32 /dev/urandom > FILE`. PackageError (one line) otherwise."""
    path = Path(path)
    try:
        key = read_regular(path.resolve(), KEY_MAX_BYTES)
    except NotRegular:
        raise PackageError(f"{path}: not a regular file (a key file holds "
                           f"{KEY_MIN_BYTES}-{KEY_MAX_BYTES} bytes)") from None
    except OSError as exc:
        raise PackageError(f"{path}: cannot read the key ({exc.strerror or exc})") from None
    if key is None:
        raise PackageError(f"{path}: larger than {KEY_MAX_BYTES} bytes (not a key file?)")
    if len(key) < KEY_MIN_BYTES:
        raise PackageError(f"{path}: a key needs at least {KEY_MIN_BYTES} bytes, this one has {len(key)} "
                           f"(e.g. head -c 32 /dev/urandom > FILE)")
    return key


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
    if not isinstance(name, str) or name_problem(name):   # the one name rule (codegen.names)
        raise PackageError(f"{path}: name: not a package entry name")
    files = doc.get("files")
    if not isinstance(files, dict) or not files:
        raise PackageError(f"{path}: files: missing or empty")
    for rel, digest in files.items():
        if not isinstance(rel, str) or not PACKAGE_PATH.fullmatch(rel):
            raise PackageError(f"{path}: files: {str(rel)[:60]!r} is not a path a package may hold")
        if not isinstance(digest, str) or not re.fullmatch(r"[0-9a-f]{64}", digest):
            raise PackageError(f"{path}: files[{rel}]: not a sha256")
    if SIGNATURE in doc:
        _check_signature_field(path, doc[SIGNATURE])
    if doc.get("sha256") != seal_of(doc):
        raise PackageError(f"{path}: sha256: the manifest was edited after it was sealed")
    return doc


def _check_signature_field(path: Path, sig) -> None:
    if not isinstance(sig, dict) or set(sig) != {"algorithm", "hmac"} or sig["algorithm"] != SIGNATURE_ALGORITHM:
        raise PackageError(f"{path}: {SIGNATURE}: expected {{\"algorithm\": \"{SIGNATURE_ALGORITHM}\", \"hmac\": ...}}")
    if not isinstance(sig["hmac"], str) or not re.fullmatch(r"[0-9a-f]{64}", sig["hmac"]):
        raise PackageError(f"{path}: {SIGNATURE}.hmac: not 64 hex digits")


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


def check(folder: str | Path, key: bytes | None = None) -> tuple[dict, list[str]]:
    """(manifest, problems): one line per edited, missing or extra file and per entry that is
    neither a regular file nor a folder (refused unopened), and with `key` one for a manifest
    that is unsigned or whose signature does not verify; [] when the folder is exactly what the
    manifest says."""
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
    signature = signature_problem(doc, key) if key is not None else None
    return doc, ([signature] if signature else []) + problems


def copy_verified(folder: str | Path, doc: dict, dst: str | Path) -> list[str]:
    """Copy every file the manifest lists from `folder` into `dst`, each from bytes read once and
    hashed again: what is built afterwards is exactly what was checked, even if the folder changes
    after `check` (a file swapped in between is a problem line, not a build input)."""
    folder, dst = Path(folder), Path(dst)
    problems = []
    for rel, digest in sorted(doc["files"].items()):
        try:
            data = read_regular(folder / rel, MAX_FILE_BYTES)
        except OSError as exc:
            problems.append(f"changed during the check: {rel} ({exc.strerror or exc})")
            continue
        if data is None or sha256_bytes(data) != digest:
            problems.append(f"changed during the check: {rel} (sha256 differs from the manifest)")
            continue
        (dst / rel).parent.mkdir(parents=True, exist_ok=True)
        (dst / rel).write_bytes(data)
    return problems
