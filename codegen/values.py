"""Numbers read from files (controller configuration, unit parameters): one grammar, one float32 rule.

The generated C holds every parameter as a float32, so a range is checked on the value *after*
rounding: 1e-50 for a positive limit would become 0 and 0.9999999999999999 for a value below 1
would become 1. A nonzero value must round to a normal float32 (no 0, no subnormal: the flight
code's FP environment may flush those). Every unit's parameter reader calls `float32_in` (or
`real` for a value that stays float64), so the rule lives here only.

Number grammar for text (files whose numbers are not parsed by JSON/TOML, and flags): ASCII
decimal digits, an optional sign, point and exponent; no underscores, no other digits
(`DECIMAL_TEXT`, `INTEGER_TEXT`). In a parsed file a number is an int or float, never a bool
or a string; `toml_number_problem` refuses TOML's own extensions (1_000, 0x10, 0o7, 0b1).
"""
from __future__ import annotations

import math
import re
import tomllib
from pathlib import Path

import numpy as np

from codegen import reading
from codegen.errors import CodegenError

FLOAT32_MAX = float(np.finfo(np.float32).max)
FLOAT32_TINY = float(np.finfo(np.float32).tiny)     # smallest normal float32, 2^-126

DECIMAL_TEXT = re.compile(r"[+-]?(?:[0-9]+(?:\.[0-9]*)?|\.[0-9]+)(?:[eE][+-]?[0-9]+)?")
INTEGER_TEXT = re.compile(r"[+-]?[0-9]+")
DIGITS_TEXT = re.compile(r"[0-9]+")       # str.isdigit() and int() also take other scripts' digits


def show(value, n: int = 40) -> str:
    """repr clipped to n characters (a value from a file may be huge)."""
    if isinstance(value, int) and value.bit_length() > 200:     # repr of a huge int is slow or refused
        return f"an integer of about {int(value.bit_length() * math.log10(2)) + 1} digits"
    text = repr(value)
    return text if len(text) <= n else text[:n - 3] + "..."


def is_number(value) -> bool:
    """An int or float from a parsed file; a bool is not a number."""
    return isinstance(value, (int, float)) and not isinstance(value, bool)


def real(value, key: str, error: type[CodegenError] = CodegenError) -> float:
    """The float64 of a parsed number, finite and within float32's range, or a one-line `error`."""
    if not is_number(value):
        raise error(f"{key}: must be a number, got {show(value)}")
    try:
        x = float(value)
    except OverflowError:        # an integer of hundreds of digits
        raise error(f"{key}: must be finite (and within float32), got {show(value)}") from None
    if not math.isfinite(x) or abs(x) > FLOAT32_MAX:
        raise error(f"{key}: must be finite (and within float32), got {show(value)}")
    return x


def _bound_text(low, high, low_open: bool, high_open: bool) -> str:
    if high is None:
        return f"{'>' if low_open else '>='} {low:g}"
    if low is None:
        return f"{'<' if high_open else '<='} {high:g}"
    return f"in {'(' if low_open else '['}{low:g}, {high:g}{')' if high_open else ']'}"


def float32_in(value, key: str, low: float | None = None, high: float | None = None, *,
               low_open: bool = False, high_open: bool = False, unit: str = "",
               error: type[CodegenError] = CodegenError) -> np.float32:
    """The float32 the C will hold for a parsed number, checked against [low, high] (ends open as
    told) after rounding; a nonzero value that rounds to 0 or a subnormal is refused."""
    x = real(value, key, error)
    f = np.float32(x)
    if x != 0.0 and not abs(float(f)) >= FLOAT32_TINY:
        raise error(f"{key}: {x!r} rounds to {'0' if f == 0 else 'a subnormal'} in float32 (the generated C "
                    f"holds float32; nonzero values need magnitude >= {FLOAT32_TINY:.4g})")
    y = float(f)
    below = low is not None and (y < low or (low_open and y == low))
    above = high is not None and (y > high or (high_open and y == high))
    if below or above:
        rounded = "" if y == x else f" (as float32: {y!r})"
        unit_text = f" {unit}" if unit else ""
        raise error(f"{key}: must be {_bound_text(low, high, low_open, high_open)}{unit_text}, got {x!r}{rounded}")
    return f


def integer_in(value, key: str, low: int, high: int, error: type[CodegenError] = CodegenError) -> int:
    """A parsed integer (not a bool, not a float) in [low, high]."""
    if not isinstance(value, int) or isinstance(value, bool):
        raise error(f"{key}: must be an integer, got {show(value)}")
    if not low <= value <= high:
        raise error(f"{key}: must be in [{low}, {high}], got {show(value)}")
    return value


# A TOML token outside strings and comments that starts like a number (keys start with a letter
# in every staregen schema; a digit-led key is an unknown key anyway).
_TOML_WORD = re.compile(r"[A-Za-z0-9_.+\-:]+")
_TOML_NUMBER_START = re.compile(r"[+-]?[0-9]")


def _toml_code(text: str) -> str:
    """The text with strings and comments blanked (so only keys, numbers and punctuation remain)."""
    out, i, n = [], 0, len(text)
    while i < n:
        for quote in ('"""', "'''", '"', "'"):
            if text.startswith(quote, i):
                end = _string_end(text, i + len(quote), quote)
                out.append(" " * (end - i))
                i = end
                break
        else:
            if text[i] == "#":
                end = text.find("\n", i)
                end = n if end < 0 else end
                out.append(" " * (end - i))
                i = end
            else:
                out.append(text[i])
                i += 1
    return "".join(out)


def _string_end(text: str, i: int, quote: str) -> int:
    """Index just past the string that opened before i (basic strings honour backslash escapes)."""
    n = len(text)
    while i < n:
        if quote[0] == '"' and text[i] == "\\":
            i += 2
            continue
        if text.startswith(quote, i):
            return i + len(quote)
        i += 1
    return n


def toml_number_problem(text: str) -> str | None:
    """None, or what breaks the file number grammar in TOML text that tomllib accepted: a number
    written with '_' separators or as 0x/0o/0b (decimal ASCII digits only)."""
    for m in _TOML_WORD.finditer(_toml_code(text)):
        word = m.group()
        if not _TOML_NUMBER_START.match(word):
            continue
        if "_" in word or re.match(r"[+-]?0[xob]", word):
            line = text.count("\n", 0, m.start()) + 1
            return f"line {line}: number {word[:40]!r}: write plain decimal digits (no '_', no 0x/0o/0b)"
    return None


def read_parameter_file(path: str | Path, error: type[CodegenError] = CodegenError) -> dict:
    """The parsed mapping of a unit's .toml or .json parameter file: a regular file, read capped,
    strict JSON or TOML without TOML's own number extensions; every problem one line naming the file."""
    path = Path(path)
    if path.suffix not in (".toml", ".json"):
        raise error(f"{path}: parameter file must end in .toml or .json")
    try:
        text = reading.read_text(path)
    except reading.InputFileError as exc:
        raise error(str(exc)) from None
    try:
        data = tomllib.loads(text) if path.suffix == ".toml" else reading.parse_json(text)
    except (ValueError, RecursionError) as exc:   # syntax, duplicate keys, NaN, integers of > 4300 digits
        first_line = str(exc).splitlines()[0] if str(exc) else "nested too deeply"
        raise error(f"{path}: not valid {path.suffix[1:].upper()}: {first_line}") from None
    problem = toml_number_problem(text) if path.suffix == ".toml" else None
    if problem:
        raise error(f"{path}: {problem}")
    return data
