"""The scenario file (`scenario.toml`): one reading of paper 001 Table 6's sensor and actuator
errors, written out so that every run records which reading it flew. Schema in docs/scenario.md.

Table 6 states each error as a constant and a random value ("3σ" for the star sensor, "1σ" for the
gyro and the wheels, wheels in "nm"). Which σ a value is, whether it applies per axis or to the
3-axis magnitude, and how often a random error is drawn are choices; the file states them and
`resolve` turns them into the SI `ErrorModel` of host.plant.error_model.

Like the controller configuration (codegen/package/config.py) the file has a fixed set of tables
and keys (unknown or missing ones are errors), an integer `version` and a `sha256` seal over the
canonical form of its values, so comments and layout may change but a value may not without
re-sealing (`staregen scenario seal FILE`). Every error is one line `<file>: <key>: <reason>`.
"""
from __future__ import annotations

import hashlib
import json
import math
import re
import tomllib
from dataclasses import dataclass
from pathlib import Path

from codegen import atomic, reading
# the controller configuration's canonical form (reals as float.hex) and value display: one
# definition of "the same values" and of a one-line shown value across the sealed files
from codegen.package.config import canonical_form, check_format_version, show_value as show
from host.core.constants import ARCSEC
from host.errors import HostError
from host.plant.error_model import DEG_PER_HOUR, ErrorModel, ErrorSource

FORMAT = "staregen.scenario"
VERSION = 1
READING_PATTERN = re.compile(r"[a-z0-9][a-z0-9_-]{0,39}")
MAX_FILE_BYTES = 64 * 1024
MAX_MAGNITUDE = 1e6          # in the file's units: nothing physical comes near it
# A draw period far below the 0.02 s plant step only costs memory (one draw per period of the
# whole run), so the floor keeps a run's draws bounded; the ceiling is one hour.
MIN_PERIOD_S = 1e-3
MAX_PERIOD_S = 3600.0
SIGMA_MULTIPLES = {"1sigma": 1.0, "2sigma": 2.0, "3sigma": 3.0}
APPLIES_TO = ("axis", "norm")


@dataclass(frozen=True)
class SourceKeys:
    """One source's table: its key names (with their unit) and the SI value of one file unit."""
    table: str
    constant: str
    random: str
    unit_si: float
    unit_name: str
    si_name: str
    comment: str


SOURCES = (
    SourceKeys("star_sensor", "constant_arcsec", "random_arcsec", ARCSEC, "arcsec", "rad",
               "on each 3-1-2 Euler angle of A_bo"),
    SourceKeys("gyro", "constant_deg_per_h", "random_deg_per_h", DEG_PER_HOUR, "deg/h", "rad/s",
               "on each axis of omega_b"),
    SourceKeys("wheels", "constant_Nm", "random_Nm", 1.0, "N*m", "N*m", "on each wheel's torque"),
)
TABLES = tuple(s.table for s in SOURCES)
TOP_KEYS = ("format", "version", "reading", "sha256", *TABLES)


class ScenarioError(HostError):
    """A rejected scenario file: one line `<file>: <key>: <reason>`."""

    def __init__(self, message: str):
        super().__init__(_one_line(message))


def _one_line(text: str) -> str:
    """Escape every character str.splitlines() would break on (a quoted TOML key may hold one)."""
    return re.sub(r"[\n\r\v\f\x1c-\x1e\x85\u2028\u2029]", lambda m: repr(m.group())[1:-1], text)


def _name(key) -> str:
    """A key as shown in a message: plain names as they are, anything else repr'd and truncated."""
    return key if isinstance(key, str) and re.fullmatch(r"[A-Za-z0-9_-]{1,40}", key) else show(key)


# ----------------------------------------------------------------------------- readings

def _source_values(constant: float, random: float, random_is: str, period: float, applies_to: str = "axis") -> dict:
    return {"constant": [constant] * 3, "random": [random] * 3, "random_is": random_is,
            "random_applies_to": applies_to, "noise_period_s": period}


def _tables(star: dict, gyro: dict, wheels: dict) -> dict:
    """{table: {key: value}} from per-source values keyed generically (constant/random)."""
    out = {}
    for keys, values in zip(SOURCES, (star, gyro, wheels)):
        out[keys.table] = {keys.constant: values["constant"], keys.random: values["random"],
                           "random_is": values["random_is"], "random_applies_to": values["random_applies_to"],
                           "noise_period_s": values["noise_period_s"]}
    return out


# reading name -> (one-line description, its source tables). Adding a reading is one entry here.
READINGS: dict[str, tuple[str, dict]] = {
    "table6": (
        "Table 6 as read so far: star 3\" as 3σ per axis, gyro and wheels as 1σ per axis, "
        "'nm' as N·m, new draws every 0.1 s control period",
        _tables(star=_source_values(3.0, 3.0, "3sigma", 0.1),
                gyro=_source_values(0.15, 0.15, "1sigma", 0.1),
                wheels=_source_values(0.01, 0.01, "1sigma", 0.1)),
    ),
}
# The commands' default (--scenario absent): the reading the calibration study chose by fitting the
# Table 1 PID's rows of Tables 8-9 (BENCHMARKS.md, "Calibration of Table 6"); the simulators' own
# default (host.sim.simulator.SimConfig) stays the literal `table6` reading.
DEFAULT_READING = "norm-star_norm-gyro_mnm-wheels"

# The calibration study's candidates (host.tune.calibrate, docs/scenario.md "Readings"): every
# combination of one defensible reading per source. A "norm" reading takes Table 6's values as the
# magnitude of the 3-axis error: the constant is split equally over the axes (value/√3 on each) and
# the random value is k·σ of the RMS magnitude (σ per axis = value/(k·√3)).
SQRT3 = math.sqrt(3.0)
STAR_READINGS = {
    "axis": ("star 3\" constant and 3\" (3σ) on each angle",
             _source_values(3.0, 3.0, "3sigma", 0.1)),
    "norm": ("star 3\" constant and 3\" (3σ) as the 3-axis magnitude",
             _source_values(3.0 / SQRT3, 3.0, "3sigma", 0.1, "norm")),
    "rnorm": ("star 3\" constant on each angle, 3\" (3σ) random as the 3-axis magnitude",
              _source_values(3.0, 3.0, "3sigma", 0.1, "norm")),
}
GYRO_READINGS = {
    "axis": ("gyro 0.15°/h constant and 0.15°/h (1σ) on each axis", _source_values(0.15, 0.15, "1sigma", 0.1)),
    "norm": ("gyro 0.15°/h constant and 0.15°/h (1σ) as the 3-axis magnitude",
             _source_values(0.15 / SQRT3, 0.15, "1sigma", 0.1, "norm")),
}
WHEEL_READINGS = {
    "held": ("wheels 'nm' as N·m, 0.01 N·m (1σ) per wheel drawn each 0.1 s control period",
             _source_values(0.01, 0.01, "1sigma", 0.1)),
    "white": ("wheels 'nm' as N·m, 0.01 N·m (1σ) per wheel drawn each 0.02 s plant step",
              _source_values(0.01, 0.01, "1sigma", 0.02)),
    "norm": ("wheels 'nm' as N·m, 0.01 N·m (1σ) as the 3-wheel magnitude, drawn each control period",
             _source_values(0.01 / SQRT3, 0.01, "1sigma", 0.1, "norm")),
    "mnm": ("wheels 'nm' as mN·m: 1e-5 N·m constant and (1σ) per wheel, drawn each control period",
            _source_values(1e-5, 1e-5, "1sigma", 0.1)),
}


def candidate_readings() -> dict[str, tuple[str, dict]]:
    """name -> (description, tables) of every combination but table6's own (axis, axis, held)."""
    out = {}
    for s_name, (s_text, star) in STAR_READINGS.items():
        for g_name, (g_text, gyro) in GYRO_READINGS.items():
            for w_name, (w_text, wheels) in WHEEL_READINGS.items():
                if (s_name, g_name, w_name) == ("axis", "axis", "held"):
                    continue
                out[f"{s_name}-star_{g_name}-gyro_{w_name}-wheels"] = (
                    f"{s_text}; {g_text}; {w_text}", _tables(star=star, gyro=gyro, wheels=wheels))
    return out


READINGS.update(candidate_readings())


# ----------------------------------------------------------------------------- validation

def _real(v, key: str) -> float:
    if not isinstance(v, (int, float)) or isinstance(v, bool):
        raise ScenarioError(f"{key}: must be a number, got {show(v)}")
    if isinstance(v, float) and not math.isfinite(v):
        raise ScenarioError(f"{key}: must be finite, got {show(v)}")
    if abs(v) > MAX_MAGNITUDE:   # before float(): an integer may be too large for a float
        raise ScenarioError(f"{key}: must be within ±{MAX_MAGNITUDE:g}, got {show(v)}")
    return float(v)


def _vec3(v, key: str, nonnegative: bool) -> list[float]:
    if not isinstance(v, list) or len(v) != 3:
        raise ScenarioError(f"{key}: must be a list of 3 numbers (one per axis), got {show(v)}")
    out = [_real(x, f"{key}[{i}]") for i, x in enumerate(v)]
    for i, x in enumerate(out):
        if nonnegative and x < 0:
            raise ScenarioError(f"{key}[{i}]: a random error must not be negative, got {x:g}")
    return out


def _choice(v, key: str, allowed) -> str:
    if not isinstance(v, str) or v not in allowed:
        raise ScenarioError(f"{key}: must be one of {', '.join(map(repr, allowed))}; got {show(v)}")
    return v


def _period(v, key: str) -> float:
    x = _real(v, key)
    if not MIN_PERIOD_S <= x <= MAX_PERIOD_S:
        raise ScenarioError(f"{key}: must be in [{MIN_PERIOD_S:g}, {MAX_PERIOD_S:g}] s, got {x:g}")
    return x


def _check_table(keys: SourceKeys, got) -> dict:
    table = keys.table
    if got is None:
        raise ScenarioError(f"{table}: missing table [{table}]")
    if not isinstance(got, dict):
        raise ScenarioError(f"{table}: must be a table [{table}], got {show(got)}")
    known = (keys.constant, keys.random, "random_is", "random_applies_to", "noise_period_s")
    for key in got:
        if key not in known:
            raise ScenarioError(f"{table}.{_name(key)}: unknown key (known in [{table}]: {', '.join(known)})")
    for key in known:
        if key not in got:
            raise ScenarioError(f"{table}.{key}: missing key")
    out = {keys.constant: _vec3(got[keys.constant], f"{table}.{keys.constant}", nonnegative=False),
           keys.random: _vec3(got[keys.random], f"{table}.{keys.random}", nonnegative=True),
           "random_is": _choice(got["random_is"], f"{table}.random_is", tuple(SIGMA_MULTIPLES)),
           "random_applies_to": _choice(got["random_applies_to"], f"{table}.random_applies_to", APPLIES_TO),
           "noise_period_s": _period(got["noise_period_s"], f"{table}.noise_period_s")}
    # a magnitude is one number: three different values would not say which axis gets what
    if out["random_applies_to"] == "norm" and len(set(out[keys.random])) != 1:
        raise ScenarioError(f"{table}.{keys.random}: with random_applies_to = \"norm\" the three values "
                            f"state one magnitude and must be equal, got {out[keys.random]}")
    return out


def _check_header(data: dict) -> None:
    for key in data:
        if key not in TOP_KEYS:
            raise ScenarioError(f"{_name(key)}: unknown key or table (known: {', '.join(TOP_KEYS)})")
    for key in ("format", "version", "reading"):
        if key not in data:
            raise ScenarioError(f"{key}: missing key")
    check_format_version(data, FORMAT, VERSION, ScenarioError)
    reading = data.get("reading")
    if not isinstance(reading, str) or not READING_PATTERN.fullmatch(reading):
        raise ScenarioError(f"reading: must be a name of 1-40 characters a-z, 0-9, _ or - "
                            f"(starting with a letter or digit), got {show(reading)}")


def check_values(data) -> dict:
    """Every rule but the seal; returns the normalised values (reals as float, without the seal)."""
    if not isinstance(data, dict):
        raise ScenarioError(f"the scenario must be a TOML table, got {type(data).__name__}")
    _check_header(data)
    values = {"format": FORMAT, "version": VERSION, "reading": data["reading"]}
    for keys in SOURCES:
        values[keys.table] = _check_table(keys, data.get(keys.table))
    return values


def values_sha256(data: dict) -> str:
    """sha256 of the canonical text of the values (reals as float.hex, so 3 and 3.0 hash alike)."""
    values = check_values({k: v for k, v in data.items() if k != "sha256"})
    text = json.dumps(canonical_form(values), sort_keys=True, separators=(",", ":"), ensure_ascii=True)
    return hashlib.sha256(text.encode("ascii")).hexdigest()


# ----------------------------------------------------------------------------- resolution

def _resolve_source(keys: SourceKeys, table: dict) -> ErrorSource:
    k = SIGMA_MULTIPLES[table["random_is"]]
    # value/k first, then the unit: with k = 3 a stated 3″ is exactly 1.0 · ARCSEC, as Table 6's
    # reading is written in host.plant.error_model
    divisor = k if table["random_applies_to"] == "axis" else k * math.sqrt(3.0)
    return ErrorSource(bias=tuple(x * keys.unit_si for x in table[keys.constant]),
                       sigma=tuple((x / divisor) * keys.unit_si for x in table[keys.random]),
                       period=table["noise_period_s"])


def resolve(values: dict) -> ErrorModel:
    """The SI ErrorModel of a scenario's values (validated first; a `sha256` key is ignored)."""
    v = check_values({k: x for k, x in values.items() if k != "sha256"})
    star, gyro, wheels = (_resolve_source(keys, v[keys.table]) for keys in SOURCES)
    return ErrorModel(reading=v["reading"], star=star, gyro=gyro, wheels=wheels)


# ----------------------------------------------------------------------------- the scenario

@dataclass(frozen=True)
class Scenario:
    """A validated scenario: its reading's name, its values (no seal), the resolved errors."""
    reading: str
    values: dict
    errors: ErrorModel
    file: str | None = None

    @property
    def sha256(self) -> str:
        return values_sha256(self.values)

    def describe(self) -> dict:
        """What a run records of the scenario it flew (JSON-able)."""
        return {"reading": self.reading, "sha256": self.sha256, "file": self.file,
                "values": json.loads(json.dumps(self.values))}


def from_values(data: dict, file: str | None = None) -> Scenario:
    values = check_values({k: v for k, v in data.items() if k != "sha256"})
    return Scenario(reading=values["reading"], values=values, errors=resolve(values), file=file)


def from_reading(name: str) -> Scenario:
    """The scenario of a named reading in READINGS."""
    if name not in READINGS:
        raise ScenarioError(f"reading: unknown reading {show(name)} (known: {', '.join(READINGS)})")
    tables = READINGS[name][1]
    return from_values({"format": FORMAT, "version": VERSION, "reading": name, **tables})


def default_scenario() -> Scenario:
    return from_reading(DEFAULT_READING)


# ----------------------------------------------------------------------------- files

def _read(path: Path) -> dict:
    try:
        raw = reading.read_bytes(path, MAX_FILE_BYTES)     # regular files only: a FIFO would block
    except reading.FileTooLargeError:
        raise ScenarioError(f"{path}: larger than {MAX_FILE_BYTES // 1024} KiB; not a scenario file") from None
    except reading.InputFileError as exc:
        raise ScenarioError(str(exc)) from None
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError:
        raise ScenarioError(f"{path}: not UTF-8 text") from None
    try:
        return tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:   # also duplicate keys and tables
        raise ScenarioError(f"{path}: not valid TOML: {str(exc).splitlines()[0]}") from None
    except RecursionError:
        raise ScenarioError(f"{path}: not valid TOML: nested too deeply") from None


def _check_seal(data: dict) -> None:
    seal = data.get("sha256")
    if not isinstance(seal, str) or not re.fullmatch(r"[0-9a-f]{64}", seal):
        raise ScenarioError(f"sha256: missing or not 64 lower-case hex digits, got {show(seal)} "
                            "(check the values, then run `staregen scenario seal FILE`)")
    actual = values_sha256(data)
    if actual != seal:
        raise ScenarioError(f"sha256: mismatch: the values hash to {actual[:16]}..., the file states "
                            f"{seal[:16]}... (a value was edited after sealing; check it, then run "
                            "`staregen scenario seal FILE`)")


def load(path: str | Path) -> Scenario:
    """Read, validate and check the seal of a scenario file; every error is one ScenarioError line."""
    path = Path(path)
    data = _read(path)
    try:
        scenario = from_values(data, file=str(path))
        _check_seal(data)
    except ScenarioError as exc:
        raise ScenarioError(f"{path}: {exc}") from None
    return scenario


def _toml_real(x: float) -> str:
    text = repr(float(x))
    return text if any(c in text for c in ".en") else text + ".0"


def _toml_vec(v) -> str:
    return "[" + ", ".join(_toml_real(x) for x in v) + "]"


def _table_toml(keys: SourceKeys, t: dict) -> str:
    return f"""[{keys.table}]   # {keys.comment}
{keys.constant} = {_toml_vec(t[keys.constant])}   # {keys.unit_name}, constant error per axis (any sign)
{keys.random} = {_toml_vec(t[keys.random])}   # {keys.unit_name}, stated random error (>= 0)
random_is = "{t["random_is"]}"   # the stated random value is k*sigma: "1sigma" | "2sigma" | "3sigma"
random_applies_to = "{t["random_applies_to"]}"   # "axis": each axis; "norm": RMS magnitude of the 3-axis error
noise_period_s = {_toml_real(t["noise_period_s"])}   # s, a new random draw every period, held in between
"""


def to_toml(scenario: Scenario) -> str:
    """The file text with comments and its seal."""
    v = scenario.values
    description = READINGS.get(scenario.reading, ("a reading of its own",))[0]
    tables = "\n".join(_table_toml(keys, v[keys.table]) for keys in SOURCES)
    return f"""# staregen scenario: one reading of paper 001 Table 6's sensor and actuator errors.
# Schema: docs/scenario.md. Resolved per axis to SI: bias = constant, sigma = random / k
# (random / (k*sqrt(3)) for "norm"); measured = true + bias + N(0, sigma^2), drawn every period.
# After editing a value, re-seal with `staregen scenario seal FILE` (the seal detects silent edits).
format = "{FORMAT}"
version = {VERSION}
# {_one_line(description)}
reading = "{scenario.reading}"
sha256 = "{scenario.sha256}"

{tables}"""


def write(scenario: Scenario, path: str | Path) -> Path:
    """Write the commented, sealed file atomically (a killed run leaves no half-written file)."""
    path = Path(path)
    if path.is_dir():
        raise ScenarioError(f"{path}: is a directory")
    try:
        return atomic.write_text(path, to_toml(scenario))
    except OSError as exc:
        raise ScenarioError(f"{path}: cannot write ({exc.strerror or exc})") from None


_SEAL_LINE = re.compile(r'^sha256[ \t]*=[ \t]*("[^"\n]*"|\'[^\'\n]*\')(?P<tail>[ \t]*(#[^\n]*)?)$', re.M)
_FIRST_TABLE = re.compile(r"^[ \t]*\[", re.M)


def _with_seal(path: Path, text: str, has_seal: bool, digest: str) -> str:
    """The text with its seal line set to `digest`: rewritten in place, or (when the file has no
    seal yet) inserted before the first table, where it is still a top-level key."""
    new = f'sha256 = "{digest}"'
    lines = list(_SEAL_LINE.finditer(text))
    if has_seal:
        if len(lines) != 1:
            raise ScenarioError(f"{path}: sha256: expected exactly one top-level line `sha256 = \"...\"` to rewrite")
        return _SEAL_LINE.sub(lambda m: new + m.group("tail"), text)
    first_table = _FIRST_TABLE.search(text)
    at = first_table.start() if first_table else len(text)
    prefix = text[:at] if not at or text[:at].endswith("\n") else text[:at] + "\n"
    return prefix + new + "\n" + text[at:]


def seal(path: str | Path) -> tuple[str, bool]:
    """Recompute the seal of a hand-edited file after validating every value; rewrites only the
    `sha256 = "..."` line (comments and layout stay). Returns (seal, whether it changed)."""
    path = Path(path)
    data = _read(path)
    try:
        digest = from_values(data).sha256
    except ScenarioError as exc:
        raise ScenarioError(f"{path}: {exc}") from None
    if data.get("sha256") == digest:
        return digest, False
    text = _with_seal(path, path.read_text(encoding="utf-8"), "sha256" in data, digest)
    try:   # the new text must load sealed before it replaces the file
        _check_seal(tomllib.loads(text))
    except (tomllib.TOMLDecodeError, ScenarioError):
        raise ScenarioError(f"{path}: sha256: cannot rewrite the seal line in place; "
                            "write the file anew with `staregen scenario init`") from None
    try:
        atomic.write_text(path, text)
    except OSError as exc:
        raise ScenarioError(f"{path}: cannot write ({exc.strerror or exc})") from None
    return digest, True
