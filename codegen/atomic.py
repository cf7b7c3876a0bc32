"""Atomic file output: a killed run leaves either the old file or the new one, never half of one.

Every layer writes its artifacts through these helpers (write to a temporary sibling, fsync,
then os.replace, which is atomic on POSIX within one filesystem).

A whole output folder (`directory`) is written under a lock beside it (`.<name>.lock`: a second
run into the same folder fails at once); its temporaries are named `.<name>.<pid>.XXXXXXXX.tmp`
(and `.old`) so that a later run removes those of a killed run, and nothing else.
"""
from __future__ import annotations

import fcntl
import json
import os
import re
import shutil
import tempfile
from contextlib import contextmanager
from pathlib import Path
from typing import Iterator

import numpy as np

from codegen.errors import CodegenError

LOCK_ATTEMPTS = 5   # a releasing run removes its lock file; reopen when it vanished under us


def _umask_mode(base: int = 0o666) -> int:
    """Permissions an ordinary open() would give (mkstemp makes 0600 files)."""
    mask = os.umask(0)
    os.umask(mask)
    return base & ~mask


def write_bytes(path: str | os.PathLike, data: bytes) -> Path:
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
    try:
        with os.fdopen(fd, "wb") as fh:
            fh.write(data)
            fh.flush()
            os.fsync(fh.fileno())
        os.chmod(tmp, _umask_mode())
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise
    return path


def write_files(files: dict[Path, bytes]) -> list[Path]:
    """Several files, all or nothing as far as POSIX allows: every temporary is written and synced
    first; only then are they renamed into place (a failure before that leaves no file changed)."""
    temps: list[tuple[str, Path]] = []
    try:
        for path, data in files.items():
            path.parent.mkdir(parents=True, exist_ok=True)
            fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
            temps.append((tmp, path))
            with os.fdopen(fd, "wb") as fh:
                fh.write(data)
                fh.flush()
                os.fsync(fh.fileno())
            os.chmod(tmp, _umask_mode())
        for tmp, path in temps:
            os.replace(tmp, path)
    except BaseException:
        for tmp, _ in temps:
            Path(tmp).unlink(missing_ok=True)
        raise
    return [path for _, path in temps]


def write_text(path: str | os.PathLike, text: str) -> Path:
    return write_bytes(path, text.encode("utf-8"))


def write_json(path: str | os.PathLike, obj, indent: int = 2) -> Path:
    """Strict JSON: a NaN or infinity is refused (json.dumps would write a bare NaN, which no JSON reader takes)."""
    try:
        text = json.dumps(obj, indent=indent, sort_keys=False, allow_nan=False)
    except ValueError:
        raise CodegenError(f"{path}: not written: a value is NaN or infinite, which JSON cannot hold") from None
    return write_text(path, text + "\n")


@contextmanager
def writing(path: str | os.PathLike, suffix: str = "") -> Iterator[Path]:
    """Yield a temporary path to write (e.g. by np.savez or savefig); it replaces `path` on success."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp" + suffix, dir=path.parent)
    os.close(fd)
    try:
        yield Path(tmp)
        os.chmod(tmp, _umask_mode())
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise


def write_npz(path: str | os.PathLike, arrays: dict) -> Path:
    """A compressed .npz of named arrays, written atomically."""
    with writing(path, suffix=".npz") as tmp:
        with open(tmp, "wb") as fh:
            np.savez_compressed(fh, **arrays)
    return Path(path)


class FolderInUse(CodegenError):
    """Another run holds the output folder's lock."""


def lock_path(path: Path) -> Path:
    return path.with_name(f".{path.name}.lock")


def _open_lock(path: Path) -> int | None:
    """The locked descriptor of `path`'s lock file, or None when the file vanished between open
    and flock (retry)."""
    lock = lock_path(path)
    fd = os.open(lock, os.O_RDWR | os.O_CREAT | os.O_NOFOLLOW | os.O_CLOEXEC, 0o644)
    try:
        fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
    except BlockingIOError:
        os.close(fd)
        raise FolderInUse(f"output folder {path} is in use by another run "
                          f"(lock {lock.name} held); wait for it or choose another folder") from None
    try:
        same = os.stat(lock, follow_symlinks=False).st_ino == os.fstat(fd).st_ino
    except FileNotFoundError:
        same = False
    if not same:
        os.close(fd)
        return None
    return fd


@contextmanager
def locked(path: str | os.PathLike) -> Iterator[None]:
    """Hold the lock of output folder `path` (fcntl.flock on `.<name>.lock` beside it, which the
    holder removes on release); FolderInUse when another run holds it."""
    path = Path(path)
    for _ in range(LOCK_ATTEMPTS):
        fd = _open_lock(path)
        if fd is not None:
            break
    else:
        raise FolderInUse(f"cannot lock output folder {path}: {lock_path(path).name} keeps being replaced")
    try:
        yield
    finally:
        lock_path(path).unlink(missing_ok=True)   # while still held: a waiter that opened it sees another inode
        os.close(fd)


def _temp_prefix(path: Path) -> str:
    return f".{path.name}.{os.getpid()}."


def _stale_pattern(path: Path) -> re.Pattern:
    """Names of this folder's temporaries (mkdtemp adds 8 characters of [a-z0-9_])."""
    return re.compile(re.escape(f".{path.name}.") + r"(\d+)\.[a-z0-9_]{8}\.(?:tmp|old)")


def _alive(pid: int) -> bool:
    if pid <= 0 or pid == os.getpid():
        return True   # never ours to judge: 0 would signal our own process group
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except (PermissionError, OverflowError):
        return True
    return True


def remove_stale(path: Path) -> list[Path]:
    """Remove the temporaries of `path` that a dead run left (call with the folder's lock held);
    returns what was removed."""
    pattern, removed = _stale_pattern(path), []
    for entry in path.parent.iterdir():
        match = pattern.fullmatch(entry.name)
        if match and entry.is_dir() and not entry.is_symlink() and not _alive(int(match.group(1))):
            shutil.rmtree(entry, ignore_errors=True)
            removed.append(entry)
    return removed


@contextmanager
def scratch(path: str | os.PathLike) -> Iterator[Path]:
    """A working folder beside output folder `path`, named as its temporaries are (a killed run's
    is removed by the next run); removed on exit."""
    path = Path(path)
    tmp = Path(tempfile.mkdtemp(prefix=_temp_prefix(path), suffix=".tmp", dir=path.parent))
    try:
        yield tmp
    finally:
        shutil.rmtree(tmp, ignore_errors=True)


def _move_in(tmp: Path, path: Path) -> None:
    """Replace `path` by folder `tmp`; the old entry goes into a fresh temporary of this run (removed
    after), and comes back if the second rename fails."""
    if not path.exists() and not path.is_symlink():
        os.replace(tmp, path)
        return
    old_dir = Path(tempfile.mkdtemp(prefix=_temp_prefix(path), suffix=".old", dir=path.parent))
    old = old_dir / path.name
    try:
        os.replace(path, old)
    except BaseException:
        old_dir.rmdir()
        raise
    try:
        os.replace(tmp, path)
    except BaseException:
        os.replace(old, path)
        old_dir.rmdir()
        raise
    shutil.rmtree(old_dir, ignore_errors=True)


@contextmanager
def directory(path: str | os.PathLike) -> Iterator[Path]:
    """Build a whole directory in a temporary sibling; it replaces `path` only on success. The
    folder is locked meanwhile (FolderInUse for a second run) and a dead run's temporaries go."""
    path = Path(path)
    if path.name in ("", ".", ".."):
        raise CodegenError(f"output folder {path}: has no name (give a folder, not '.' or '/')")
    path.parent.mkdir(parents=True, exist_ok=True)
    with locked(path):
        remove_stale(path)
        with scratch(path) as tmp:
            yield tmp
            os.chmod(tmp, _umask_mode(0o777))
            _move_in(tmp, path)
