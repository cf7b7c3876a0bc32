"""One number grammar for numbers a user types (command-line flags, target rows, tuning grids):
ASCII digits only, no digit-group underscores. Python's int() and float() accept more (`1_00`,
Arabic-Indic `٤`, full-width `１`, surrounding Unicode spaces), so the same text could mean a
number here and nothing to every other tool; these functions accept exactly the grammar below.

    integer  [+-]?[0-9]+
    real     [+-]?([0-9]+(.[0-9]*)?|.[0-9]+)([eE][+-]?[0-9]+)?   or inf, infinity, nan (any case)

Surrounding ASCII blanks (space, tab, CR, LF) are ignored. Both raise ValueError on anything else.
"""
from __future__ import annotations

import re

from codegen.values import DECIMAL_TEXT, INTEGER_TEXT

# the grammar of numbers in files (codegen.values), plus the words inf and nan that a flag may spell
INTEGER = INTEGER_TEXT
REAL = re.compile(rf"(?:{DECIMAL_TEXT.pattern})|[+-]?(?i:inf|infinity|nan)")
BLANKS = " \t\r\n"


def parse_integer(text: str) -> int:
    """The integer `text` spells in the grammar above, or ValueError."""
    if not isinstance(text, str) or not INTEGER.fullmatch(text.strip(BLANKS)):
        raise ValueError(f"not an integer in ASCII digits: {text!r:.40}")
    return int(text)   # may still raise ValueError past Python's integer-string digit limit


def parse_real(text: str) -> float:
    """The real `text` spells in the grammar above (inf and nan included: callers check them), or ValueError."""
    if not isinstance(text, str) or not REAL.fullmatch(text.strip(BLANKS)):
        raise ValueError(f"not a number in ASCII digits: {text!r:.40}")
    return float(text)
