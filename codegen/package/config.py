"""The controller configuration artifact (`controller.toml`): what the flight package bakes in
besides the network — PID gains, limits, timing, Earth constants, the entry-name prefix and
which units the package holds. Schema in docs/controller-config.md.

A file is TOML with a fixed set of tables and keys (unknown or missing ones are errors), an
integer `version`, and a `sha256` seal over the canonical form of its values (sorted keys, every
real as float.hex, integers as integers), so comments and layout may change but a value may not
without re-sealing (`staregen config seal FILE`). Every error is one line naming the key.
"""
from __future__ import annotations

import hashlib
import json
import re
import tomllib
from dataclasses import dataclass
from pathlib import Path

from codegen import atomic, reading, values
from codegen.errors import CodegenError
from codegen.names import NAME, name_problem
from codegen import units as unit_registry
from codegen.units.controller.spec import ControllerConfig

FORMAT = "staregen.controller-config"
VERSION = 1
NAME_PATTERN = NAME     # the one package-name rule: codegen.names
MAX_DWELL = 1_000_000
MAX_PERIOD_S = 10.0
FLOAT32_MAX = values.FLOAT32_MAX

# table -> key -> kind; kinds: "vec3>=0", ">0", ">=0", "[0,1)", "int>=1", "name", "units"
SCHEMA: dict[str, dict[str, str]] = {
    "package": {"name": "name", "units": "units"},
    "pid": {"kp": "vec3>=0", "ki": "vec3>=0", "kd": "vec3>=0", "integral_limit": ">0"},
    "limits": {"torque_limit": ">0"},
    "timing": {"control_period": "period", "dwell_steps": "int>=1"},
    "earth": {"a": ">0", "e2": "[0,1)", "rate": ">0", "mu": ">0"},
}
TOP_KEYS = ("format", "version", "sha256", *SCHEMA)


def known_units() -> tuple[str, ...]:
    """"controller" (required) and every registered unit that reads its own parameter file: the
    package binds those to `generate --params UNIT=FILE` at the configuration's control period."""
    kinds = unit_registry.kinds()
    return ("controller",) + tuple(sorted(k for k, kind in kinds.items() if kind.load_params is not None))


class ConfigError(CodegenError):
    """A rejected controller configuration: `<file>: <key>: <reason>`."""


@dataclass(frozen=True)
class PackageConfig:
    """A validated configuration: the package's entry prefix, its units, the controller's constants."""

    name: str
    units: tuple[str, ...]
    controller: ControllerConfig

    def __post_init__(self):
        _check(self.to_mapping())

    @property
    def param_units(self) -> tuple[str, ...]:
        """The units besides the controller (each needs its parameter file)."""
        return tuple(u for u in self.units if u != "controller")

    def to_mapping(self) -> dict:
        """The file's values as nested tables (without the seal)."""
        c = self.controller
        return {
            "format": FORMAT, "version": VERSION,
            "package": {"name": self.name, "units": list(self.units)},
            "pid": {"kp": list(c.kp), "ki": list(c.ki), "kd": list(c.kd), "integral_limit": c.integral_limit},
            "limits": {"torque_limit": c.torque_limit},
            "timing": {"control_period": c.control_period, "dwell_steps": c.dwell_steps},
            "earth": {"a": c.earth_a, "e2": c.earth_e2, "rate": c.earth_rate, "mu": c.mu},
        }

    @property
    def sha256(self) -> str:
        return values_sha256(self.to_mapping())


# ----------------------------------------------------------------------------- validation

def show_value(v) -> str:
    return values.show(v)


def check_format_version(data: dict, fmt: str, version: int, error: type[Exception]) -> None:
    """The `format` and integer `version` header every sealed TOML file of staregen starts with (the
    controller configuration, the scenario file), each defect one `error` line."""
    if data.get("format") != fmt:
        raise error(f"format: must be \"{fmt}\", got {show_value(data.get('format'))}")
    got = data.get("version")
    if not isinstance(got, int) or isinstance(got, bool):
        raise error(f"version: must be the integer {version}, got {show_value(got)}")
    if got != version:
        raise error(f"version: unsupported version {got} (this staregen reads version {version})")


def _real(v, key: str, low: float | None = None, high: float | None = None, **ends) -> float:
    """The file's float64 value, after checking its float32 rounding (what the C holds) is in range."""
    values.float32_in(v, key, low, high, error=ConfigError, **ends)
    return float(v)


def _value(kind: str, v, key: str):
    """The value of one key, normalised (reals to float), or a one-line ConfigError."""
    if kind == "name":
        problem = name_problem(v)
        if problem:
            raise ConfigError(f"{key}: {problem} (got {show_value(v)})")
        return v
    if kind == "units":
        if not isinstance(v, list) or not all(isinstance(u, str) for u in v):
            raise ConfigError(f"{key}: must be a list of unit names, got {show_value(v)}")
        known = known_units()
        for u in v:
            if u not in known:
                raise ConfigError(f"{key}: unknown unit {show_value(u)} (known: {', '.join(known)})")
        if len(set(v)) != len(v):
            raise ConfigError(f"{key}: lists a unit twice")
        if "controller" not in v:
            raise ConfigError(f"{key}: must include \"controller\" (the package's main unit)")
        return tuple(u for u in known if u in v)
    if kind == "int>=1":
        return values.integer_in(v, key, 1, MAX_DWELL, ConfigError)
    if kind == "vec3>=0":
        if not isinstance(v, list) or len(v) != 3:
            raise ConfigError(f"{key}: must be a list of 3 numbers (x, y, z), got {show_value(v)}")
        out = tuple(_real(x, f"{key}[{i}]") for i, x in enumerate(v))
        for i, x in enumerate(out):
            if x < 0:
                raise ConfigError(f"{key}[{i}]: a gain must not be negative, got {x:g}")
        return out
    if kind == ">0":
        return _real(v, key, 0.0, low_open=True)
    if kind == "period":
        return _real(v, key, 0.0, MAX_PERIOD_S, low_open=True, unit="s")
    if kind == "[0,1)":
        return _real(v, key, 0.0, 1.0, high_open=True)
    raise ValueError(f"{key}: unknown schema kind {kind!r}")


def _check(data) -> dict:
    """Every rule but the seal; returns {table: {key: normalised value}}."""
    if not isinstance(data, dict):
        raise ConfigError(f"the configuration must be a TOML table, got {type(data).__name__}")
    for key in data:
        if key not in TOP_KEYS:
            raise ConfigError(f"{key}: unknown key (known: {', '.join(TOP_KEYS)})")
    check_format_version(data, FORMAT, VERSION, ConfigError)
    values = {}
    for table, keys in SCHEMA.items():
        got = data.get(table)
        if got is None:
            raise ConfigError(f"{table}: missing table [{table}]")
        if not isinstance(got, dict):
            raise ConfigError(f"{table}: must be a table [{table}], got {show_value(got)}")
        for key in got:
            if key not in keys:
                raise ConfigError(f"{table}.{key}: unknown key (known in [{table}]: {', '.join(keys)})")
        values[table] = {}
        for key, kind in keys.items():
            if key not in got:
                raise ConfigError(f"{table}.{key}: missing key")
            values[table][key] = _value(kind, got[key], f"{table}.{key}")
    return values


def canonical_form(v):
    if isinstance(v, float):
        return v.hex()
    if isinstance(v, (list, tuple)):
        return [canonical_form(x) for x in v]
    if isinstance(v, dict):
        return {k: canonical_form(x) for k, x in v.items()}
    return v


def values_sha256(mapping: dict) -> str:
    """sha256 of the canonical text of the values (reals as float.hex, so 17 and 17.0 hash alike)."""
    values = _check({k: v for k, v in mapping.items() if k != "sha256"})
    body = {"format": FORMAT, "version": VERSION, **values}
    text = json.dumps(canonical_form(body), sort_keys=True, separators=(",", ":"), ensure_ascii=True)
    return hashlib.sha256(text.encode("ascii")).hexdigest()


def from_mapping(data: dict, sealed: bool = True) -> PackageConfig:
    """A validated PackageConfig; with sealed=True the `sha256` key must match the values."""
    v = _check(data)
    if sealed:
        seal = data.get("sha256")
        if not isinstance(seal, str) or not re.fullmatch(r"[0-9a-f]{64}", seal):
            raise ConfigError(f"sha256: missing or not 64 lower-case hex digits, got {show_value(seal)}")
        actual = values_sha256(data)
        if actual != seal:
            raise ConfigError(f"sha256: mismatch: the values hash to {actual[:16]}..., the file states "
                              f"{seal[:16]}... (a value was edited after sealing; check it, then run "
                              "`staregen config seal FILE`)")
    pid, timing, earth = v["pid"], v["timing"], v["earth"]
    controller = ControllerConfig(
        kp=pid["kp"], ki=pid["ki"], kd=pid["kd"], torque_limit=v["limits"]["torque_limit"],
        control_period=timing["control_period"], dwell_steps=timing["dwell_steps"],
        integral_limit=pid["integral_limit"], earth_a=earth["a"], earth_e2=earth["e2"],
        earth_rate=earth["rate"], mu=earth["mu"])
    return PackageConfig(v["package"]["name"], v["package"]["units"], controller)


def _read(path: Path) -> tuple[str, dict]:
    """The file's text (a capped read of a regular file) and its TOML tables."""
    try:
        text = reading.read_text(path)
    except reading.InputFileError as exc:
        raise ConfigError(str(exc)) from None
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:   # also duplicate keys and tables
        raise ConfigError(f"{path}: not valid TOML: {str(exc).splitlines()[0]}") from None
    except ValueError as exc:      # an integer of more than 4300 digits
        raise ConfigError(f"{path}: not valid TOML: {str(exc).splitlines()[0]}") from None
    except RecursionError:
        raise ConfigError(f"{path}: not valid TOML: nested too deeply") from None
    problem = values.toml_number_problem(text)
    if problem:
        raise ConfigError(f"{path}: {problem}")
    return text, data


def load(path: str | Path, sealed: bool = True) -> PackageConfig:
    """Read and validate a controller.toml; every error is one `ConfigError` line naming file and key."""
    path = Path(path)
    _, data = _read(path)
    try:
        return from_mapping(data, sealed)
    except ConfigError as exc:
        raise ConfigError(f"{path}: {exc}") from None


# ----------------------------------------------------------------------------- writing

def _toml_real(x: float) -> str:
    text = repr(float(x))
    return text if any(c in text for c in ".en") else text + ".0"


def _toml_vec(v) -> str:
    return "[" + ", ".join(_toml_real(x) for x in v) + "]"


def to_toml(cfg: PackageConfig, sources: dict[str, str] | None = None) -> str:
    """The file text with comments and its seal; `sources` adds a "# from: ..." line per table."""
    c = cfg.controller
    src = sources or {}

    def origin(table: str) -> str:
        return f"# from: {src[table]}\n" if table in src else ""

    units = ", ".join(f'"{u}"' for u in cfg.units)
    return f"""# staregen controller configuration: what the flight package bakes in besides the network.
# Schema: docs/controller-config.md. Reals in SI unless stated; the generated C rounds each to float32.
# After editing a value, re-seal with `staregen config seal FILE` (the seal guards against silent edits).
format = "{FORMAT}"
version = {VERSION}
sha256 = "{cfg.sha256}"

[package]
# Entry-name prefix: {cfg.name}_init / {cfg.name}_step / {cfg.name}_selftest, files {cfg.name}*.h/.c.
name = "{cfg.name}"
# Units in the package: "controller" (Fig. 2 with its network; required) and any of
# {", ".join(f'"{u}"' for u in known_units()[1:])} (entry {cfg.name}_<unit>; each needs
# `generate --params <unit>=FILE`, e.g. "tanh": paper 000's tanh law, docs/tanh_paper000.toml).
units = [{units}]

[pid]
{origin("pid")}# Fallback PID of paper 001 (Table 1), per axis x, y, z; errors in DEGREES:
#   M = -(kp * A_bd + ki * integral(A_bd) + kd * omega_e), then clipped to the torque limit.
kp = {_toml_vec(c.kp)}   # N*m/deg
ki = {_toml_vec(c.ki)}   # N*m/(deg*s)
kd = {_toml_vec(c.kd)}   # N*m/(deg/s)
integral_limit = {_toml_real(c.integral_limit)}   # deg*s, |integrator| bound (anti-windup; keeps the state finite)

[limits]
{origin("limits")}torque_limit = {_toml_real(c.torque_limit)}   # N*m per axis (Table 6 wheel limit)

[timing]
{origin("timing")}control_period = {_toml_real(c.control_period)}   # s, one step per period (PID integrator step)
dwell_steps = {c.dwell_steps}   # consecutive in-envelope steps before the network resumes after the PID

[earth]
{origin("earth")}a = {_toml_real(c.earth_a)}   # m, WGS-84 semi-major axis
e2 = {_toml_real(c.earth_e2)}   # WGS-84 first eccentricity squared
rate = {_toml_real(c.earth_rate)}   # rad/s, Earth rotation rate (d GMST / dt)
mu = {_toml_real(c.mu)}   # m^3/s^2, gravitational parameter
"""


def write(cfg: PackageConfig, path: str | Path, sources: dict[str, str] | None = None) -> Path:
    """Write the commented, sealed file atomically (a killed run leaves no half-written file)."""
    path = Path(path)
    if path.is_dir():
        raise ConfigError(f"{path}: is a directory")
    try:
        return atomic.write_text(path, to_toml(cfg, sources))
    except OSError as exc:
        raise ConfigError(f"{path}: cannot write ({exc.strerror or exc})") from None


_SEAL_LINE = re.compile(r'^sha256\s*=\s*"[^"\n]*"[ \t]*$', re.M)


def seal(path: str | Path) -> tuple[str, bool]:
    """Recompute the seal of a hand-edited file after validating every value; rewrites only the
    `sha256 = "..."` line (comments and layout stay). Returns (seal, whether it changed)."""
    path = Path(path)
    text, data = _read(path)
    try:
        cfg = from_mapping(data, sealed=False)
    except ConfigError as exc:
        raise ConfigError(f"{path}: {exc}") from None
    new = f'sha256 = "{cfg.sha256}"'
    lines = _SEAL_LINE.findall(text)
    if len(lines) != 1:
        raise ConfigError(f"{path}: sha256: expected exactly one top-level line `sha256 = \"...\"` to rewrite")
    changed = lines[0] != new
    if changed:
        atomic.write_text(path, _SEAL_LINE.sub(new, text))
    return cfg.sha256, changed
