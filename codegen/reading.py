"""Reading an input file: bounded by the bytes actually read, regular files only, strict JSON.

`st_size` is not trusted (/dev/zero, /proc files and FIFOs report 0 or lie): a read asks for one
byte more than the cap and refuses the file if it gets it. A device or FIFO where a file is
expected would block or never end, so only regular files are read.
"""
from __future__ import annotations

import json
import os
import stat
from pathlib import Path

from codegen.errors import CodegenError

MAX_FILE_BYTES = 64 << 20      # an artifact; configurations and parameter files are far smaller
MAX_TEXT_BYTES = 1 << 20       # a hand-written configuration or parameter file
MAX_JSON_DEPTH = 32


class InputFileError(CodegenError):
    """An input file that cannot be read: missing, not a regular file, too large, not UTF-8."""


class FileTooLargeError(InputFileError):
    """An input file longer than the reader's cap."""


def read_bytes(path: str | os.PathLike, cap: int = MAX_FILE_BYTES) -> bytes:
    """The bytes of the regular file at `path`, at most `cap` of them, or a one-line InputFileError
    naming the file (also for OSError: a missing file, a folder, no permission)."""
    path = Path(path)
    try:
        # O_NONBLOCK: opening a FIFO must not wait for a writer before fstat can refuse it
        fd = os.open(path, os.O_RDONLY | getattr(os, "O_NONBLOCK", 0))
    except FileNotFoundError:
        raise InputFileError(f"{path}: cannot read (no such file)") from None
    except OSError as exc:
        raise InputFileError(f"{path}: cannot read ({exc.strerror or exc})") from None
    if not stat.S_ISREG(os.fstat(fd).st_mode):
        os.close(fd)
        raise InputFileError(f"{path}: cannot read (not a regular file)")
    with os.fdopen(fd, "rb") as fh:
        try:
            data = fh.read(cap + 1)
        except OSError as exc:
            raise InputFileError(f"{path}: cannot read ({exc.strerror or exc})") from None
    if len(data) > cap:
        raise FileTooLargeError(f"{path}: larger than {cap} bytes")
    return data


def read_text(path: str | os.PathLike, cap: int = MAX_TEXT_BYTES) -> str:
    """`read_bytes` decoded as UTF-8."""
    try:
        return read_bytes(path, cap).decode("utf-8")
    except UnicodeDecodeError:
        raise InputFileError(f"{path}: not UTF-8 text") from None


def json_depth(text: str) -> int:
    """Deepest nesting of [ and { outside strings (counted before the recursive parser sees it)."""
    depth = current = 0
    in_string = escaped = False
    for ch in text:
        if in_string:
            escaped = not escaped and ch == "\\"
            in_string = escaped or ch != '"'
        elif ch == '"':
            in_string = True
        elif ch in "[{":
            current += 1
            depth = max(depth, current)
        elif ch in "]}":
            current -= 1
    return depth


def parse_json(text: str | bytes):
    """Strict JSON: no NaN/Infinity, no duplicate keys, at most MAX_JSON_DEPTH levels; a ValueError
    whose first line says what is wrong otherwise (the caller names the file)."""
    if isinstance(text, bytes):
        text = text.decode("utf-8")
    if json_depth(text) > MAX_JSON_DEPTH:
        raise ValueError(f"nested deeper than {MAX_JSON_DEPTH} levels")
    try:
        return json.loads(text, parse_constant=_reject_constant, object_pairs_hook=_unique_keys)
    except RecursionError:
        raise ValueError("nested too deeply") from None


def _reject_constant(name: str):
    raise ValueError(f"{name} is not JSON")


def _unique_keys(pairs: list) -> dict:
    seen = {}
    for key, value in pairs:
        if key in seen:
            shown = key if len(key) <= 40 else key[:37] + "..."
            raise ValueError(f"duplicate key {shown!r}")
        seen[key] = value
    return seen


def read_json(path: str | os.PathLike, cap: int = MAX_FILE_BYTES):
    """A strict JSON document from a capped read; every problem is one InputFileError naming the file."""
    text = read_text(path, cap)
    try:
        return parse_json(text)
    except ValueError as exc:   # JSONDecodeError, duplicates, constants, depth, integers of > 4300 digits
        raise InputFileError(f"{path}: not valid JSON: {str(exc).splitlines()[0] if str(exc) else 'too deep'}") from None
