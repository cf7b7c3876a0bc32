"""Parsing of numeric command-line values into one-line HostErrors (shared by every subcommand)."""
from __future__ import annotations

import math

from host.errors import HostError
from host.sim import scenario_file


def parse_int(text: str, what: str, minimum: int = 0, maximum: int | None = None) -> int:
    try:
        value = int(text)
    except (TypeError, ValueError):
        raise HostError(f"{what} must be an integer, got {text!r}") from None
    if value < minimum:
        raise HostError(f"{what} must be at least {minimum}, got {value}")
    if maximum is not None and value > maximum:
        raise HostError(f"{what} must be at most {maximum}, got {value}")
    return value


def parse_number(text: str, what: str, *, positive: bool = False, non_negative: bool = False,
                 minimum: float | None = None, maximum: float | None = None) -> float:
    try:
        value = float(text)
    except (TypeError, ValueError):
        raise HostError(f"{what} must be a number, got {text!r}") from None
    if not math.isfinite(value):
        raise HostError(f"{what} must be finite, got {text!r}")
    if positive and value <= 0:
        raise HostError(f"{what} must be positive, got {text}")
    if non_negative and value < 0:
        raise HostError(f"{what} must not be negative, got {text}")
    if minimum is not None and value < minimum:
        raise HostError(f"{what} must be at least {minimum:g}, got {text}")
    if maximum is not None and value > maximum:
        raise HostError(f"{what} must be at most {maximum:g}, got {text}")
    return value


SCENARIO_HELP = ("scenario file (`staregen scenario init`): the reading of Table 6's sensor and wheel errors "
                 f"(default: the built-in `{scenario_file.DEFAULT_READING}` reading, chosen by `staregen calibrate`)")


def add_scenario_argument(parser) -> None:
    parser.add_argument("--scenario", default=None, metavar="FILE", help=SCENARIO_HELP)


def load_scenario(path: str | None):
    """The --scenario file, validated (one-line error), or the default `table6` reading."""
    return scenario_file.default_scenario() if path is None else scenario_file.load(path)
