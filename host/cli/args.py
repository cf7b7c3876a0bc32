"""Parsing of numeric command-line values into one-line HostErrors (shared by every subcommand)."""
from __future__ import annotations

import math

from codegen import number_text
from host.errors import HostError
from host.sim import scenario_file


def shown(text) -> str:
    """A user's text for an error line: quoted, at most 40 characters."""
    s = repr(text)
    return s if len(s) <= 40 else s[:37] + "..."


def parse_int(text: str, what: str, minimum: int = 0, maximum: int | None = None) -> int:
    """An integer in ASCII digits (codegen.number_text: no `1_00`, no Arabic-Indic digits) within bounds."""
    try:
        value = number_text.parse_integer(text)
    except ValueError:
        raise HostError(f"{what} must be an integer in ASCII digits, got {shown(text)}") from None
    if value < minimum:
        raise HostError(f"{what} must be at least {minimum}, got {value}")
    if maximum is not None and value > maximum:
        raise HostError(f"{what} must be at most {maximum}, got {value}")
    return value


def parse_list(text: str, what: str, parse) -> tuple:
    """A comma-separated list, each item through `parse(item)`; at least one item."""
    parts = [p.strip() for p in text.split(",") if p.strip()]
    if not parts:
        raise HostError(f"{what} needs at least one value")
    return tuple(parse(p) for p in parts)


def parse_number(text: str, what: str, *, positive: bool = False, non_negative: bool = False,
                 minimum: float | None = None, maximum: float | None = None) -> float:
    """A real in ASCII digits (codegen.number_text) within bounds."""
    try:
        value = number_text.parse_real(text)
    except ValueError:
        raise HostError(f"{what} must be a number in ASCII digits, got {shown(text)}") from None
    if not math.isfinite(value):
        raise HostError(f"{what} must be finite, got {shown(text)}")
    if positive and value <= 0:
        raise HostError(f"{what} must be positive, got {text}")
    if non_negative and value < 0:
        raise HostError(f"{what} must not be negative, got {text}")
    if minimum is not None and value < minimum:
        raise HostError(f"{what} must be at least {minimum:g}, got {text}")
    if maximum is not None and value > maximum:
        raise HostError(f"{what} must be at most {maximum:g}, got {text}")
    return value


def parse_response_targets(text: str, n_targets: int) -> int:
    """--response-targets of evaluate and calibrate: `all` (the default) is every staring target, so
    `--targets central` works with the defaults; an explicit count above the targets stays an error."""
    if text.strip().lower() == "all":
        return n_targets
    return parse_int(text, "--response-targets", minimum=1, maximum=n_targets)


SCENARIO_HELP = ("scenario file (`staregen scenario init`): the reading of Table 6's sensor and wheel errors "
                 f"(default: the built-in `{scenario_file.DEFAULT_READING}` reading, chosen by `staregen calibrate`)")


def add_scenario_argument(parser) -> None:
    parser.add_argument("--scenario", default=None, metavar="FILE", help=SCENARIO_HELP)


def load_scenario(path: str | None):
    """The --scenario file, validated (one-line error), or the default `table6` reading."""
    return scenario_file.default_scenario() if path is None else scenario_file.load(path)
