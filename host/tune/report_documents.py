"""The documents `staregen report` reads (evaluate.json, result.json, calibration.json), checked
against the shape the report uses before a line of it is written: a wrong type, a missing field, a
NaN or a zero J̄ the report divides by is a one-line HostError naming the file and the field.

A shape is a small nested description: a scalar kind (REAL, NONNEG, POSITIVE, COUNT, TEXT, FLAG),
a dict of fields (a key ending in "?" may be missing; other keys are allowed), ListOf, MapOf (any
label -> one shape) or Maybe (null allowed)."""
from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path

from host.errors import HostError

REAL, NONNEG, POSITIVE, COUNT, TEXT, FLAG = "a finite number", "a number >= 0", "a number > 0", \
    "an integer >= 0", "a string", "true or false"
MAX_DOCUMENT_BYTES = 256 << 20       # a report input is a few MB at paper scale
MAX_MAGNITUDE = 1e300                # any number the report formats stays a float


@dataclass(frozen=True)
class ListOf:
    item: object
    length: int | None = None
    min_length: int = 0


@dataclass(frozen=True)
class MapOf:
    item: object


@dataclass(frozen=True)
class Maybe:
    item: object


XYZ = ListOf(REAL, 3)
SCENARIO = Maybe({"reading?": TEXT, "sha256?": Maybe(TEXT)})
TIMING = MapOf(Maybe(REAL))
ROW = {"J_A": NONNEG, "J_w": NONNEG, "J": POSITIVE, "targets": COUNT}
PAIR = {"J_A": NONNEG, "J_w": NONNEG, "J": POSITIVE}
STEP_MEAN = {"overshoot_pct": XYZ, "settling_s": XYZ, "steady_state_deg": XYZ}

EVALUATION = {
    "staring": MapOf(ROW), "staring_central?": MapOf(ROW), "step": MapOf({"mean": STEP_MEAN}),
    "frequency": MapOf({"freqs_hz": ListOf(POSITIVE, min_length=1), "amplitude_deg": ListOf(ListOf(REAL), 3)}),
    "plan?": {"targets": COUNT, "duration": POSITIVE, "response_targets": COUNT, "freqs_hz": ListOf(POSITIVE),
              "seed": COUNT, "preset?": Maybe(TEXT), "error_reading?": Maybe(TEXT)},
    "impulse?": Maybe({"t_pid_first_s": Maybe(REAL), "t_nn_back_s": Maybe(REAL), "peak_A_bd_deg": REAL,
                       "final_max_A_bd_deg": REAL}),
    "timing?": TIMING, "scenario?": SCENARIO,
}
TUNING = {
    "grid": TEXT, "triples": COUNT, "targets": COUNT, "duration": POSITIVE,
    "best": MapOf({"kp": NONNEG, "ki": NONNEG, "kd": NONNEG, "objective": NONNEG, "table1_on_grid": FLAG,
                   "table1_objective": Maybe(NONNEG)}),
    "check": {"table1": {"J": POSITIVE}, "tuned": {"J": POSITIVE}, "ratio_tuned_to_table1": POSITIVE},
    "timing?": TIMING, "scenario?": SCENARIO,
}
CALIBRATION = {
    "labels": {"table1": TEXT, "tuned": Maybe(TEXT), "network": TEXT},
    "candidates": ListOf({"reading": TEXT, "residual": NONNEG, "ratios": MapOf(REAL)}, min_length=1),
    "chosen": TEXT, "chosen_scenario?": SCENARIO,
    "prediction": {"staring": MapOf({"central": PAIR, "all": PAIR}), "step?": MapOf(STEP_MEAN)},
    "nn_to_pid_ratio": MapOf(REAL), "paper_nn_to_pid_ratio": POSITIVE,
    "scale_fit?": Maybe({"reading": TEXT, "scale": REAL, "residual": REAL,
                         "prediction": MapOf({"central": PAIR, "all": PAIR}), "nn_to_pid_ratio": MapOf(REAL)}),
    "step_model?": Maybe({"laws": MapOf({"kp": XYZ, "kd": XYZ, "settling_s": XYZ}),
                          "critically_damped_for_paper_nn_settling": {"settling_s": XYZ, "kp": XYZ, "kd": XYZ}}),
}

# `staregen simulate --controller rbf|rbf-c|rbf-arm` (host.sim.rbf_example): the fields the report reads
MAYBE_TIME = Maybe(NONNEG)
RBF_RUN = {
    "controller": TEXT, "theorem": COUNT, "period": POSITIVE, "duration": POSITIVE,
    "t_rho_5m": MAYBE_TIME, "t_rho_1m": MAYBE_TIME, "t_attitude_1deg": ListOf(MAYBE_TIME, 3),
    "delta_v": NONNEG, "torque_impulse": NONNEG, "min_rho": REAL, "weight_bound_active_steps": COUNT,
    "rms_e1?": ListOf(NONNEG, 6), "golden_mismatch_steps?": COUNT, "max_rho_diff_m?": NONNEG,
    "max_attitude_diff_deg?": NONNEG, "cycles_max?": COUNT,
}
RBF_IN_LOOP = ("golden_mismatch_steps", "max_rho_diff_m", "max_attitude_diff_deg")   # all or none

# `staregen simulate --controller gp-baseline|gp` (host.sim.gp_example): the fields the report reads
GP_RUN = {
    "controller": TEXT, "start": TEXT, "duration": POSITIVE, "n_inducing": COUNT,
    "t_settle_1deg": MAYBE_TIME, "t_settle_0p1deg": MAYBE_TIME, "steady_error_deg_mean": NONNEG,
    "steady_error_deg_max": NONNEG, "torque_rms": ListOf(NONNEG, 3), "max_abs_torque": NONNEG,
    "h_w_end": XYZ, "t_momentum_limit": ListOf(Maybe(REAL), 3), "gains_first_60s": ListOf(REAL, 2),
    "gains_last_60s": ListOf(REAL, 2), "var_fraction_first_60s": Maybe(NONNEG), "var_fraction_last_60s": Maybe(NONNEG),
    "mode?": TEXT, "golden_mismatch_steps?": COUNT, "max_angle_diff_deg?": NONNEG, "max_torque_diff?": NONNEG,
    "max_mu_diff?": NONNEG, "cycles_median?": COUNT, "cycles_max?": COUNT,
}
GP_IN_LOOP = ("mode", "golden_mismatch_steps", "max_angle_diff_deg", "max_torque_diff", "max_mu_diff")  # all or none
# `staregen basilisk --compare` (host.cli.basilisk): crosscheck.json of the staring scenario and of paper 000's
BASILISK_SIMULATORS = ListOf(TEXT, 2)
BASILISK_STARING = {
    "kind": TEXT, "simulators": BASILISK_SIMULATORS, "controller": TEXT, "errors": TEXT, "disturbances": ListOf(TEXT),
    "duration_s": POSITIVE, "targets": ListOf({"staregen": {"J_A": NONNEG, "J_w": NONNEG},
                                                 "basilisk": {"J_A": NONNEG, "J_w": NONNEG}}, min_length=1),
    "max_attitude_diff_deg": NONNEG, "max_rate_diff_deg_s": NONNEG,
    "max_relative_difference": {"J_A": NONNEG, "J_w": NONNEG}, "per_target_within_2_percent": FLAG,
    "means?": MapOf({"staregen": NONNEG, "basilisk": NONNEG, "standard_error": NONNEG,
                     "difference_in_standard_errors": Maybe(NONNEG)}),
    "means_within_spread?": FLAG,
}
BASILISK_TANH = {
    "kind": TEXT, "simulators": BASILISK_SIMULATORS, "controller": TEXT, "duration_s": POSITIVE, "dt_s": POSITIVE,
    "u_max": NONNEG, "torque_bound": POSITIVE, "torque_within_bound": FLAG, "t_settle_staregen": MAYBE_TIME,
    "t_settle_basilisk": MAYBE_TIME, "relative_difference": Maybe(REAL), "tolerance": POSITIVE, "within": FLAG,
    "max_abs_e_norm_difference": NONNEG,
}

# the names host.sim.gp_example writes (tests/host/tune/test_report.py checks they agree)
GP_CONTROLLERS = ("gp-baseline", "gp", "gp-c", "gp-arm")
GP_STARTS = ("capture", "outside")


def _label(value) -> str:
    """A value for an error line: short, on one line (a container by its type)."""
    if isinstance(value, (dict, list)):
        return f"a {'list' if isinstance(value, list) else 'JSON object'}"
    text = repr(value[:40] if isinstance(value, str) else value)
    return text if len(text) <= 32 else text[:29] + "..."


def _scalar(value, kind: str) -> bool:
    if kind == TEXT:
        return isinstance(value, str)
    if kind == FLAG:
        return isinstance(value, bool)
    if kind == COUNT:
        return isinstance(value, int) and not isinstance(value, bool) and value >= 0
    if not isinstance(value, (int, float)) or isinstance(value, bool) or not abs(value) <= MAX_MAGNITUDE:
        return False      # NaN fails the comparison; a 400-digit integer is compared without float()
    return kind == REAL or (kind == NONNEG and value >= 0) or (kind == POSITIVE and value > 0)


def check(value, shape, field: str) -> None:
    """Raise HostError("FIELD: must be ...") where `value` does not have `shape`."""
    if isinstance(shape, Maybe):
        if value is None:
            return
        shape = shape.item
    if isinstance(shape, str):
        if not _scalar(value, shape):
            raise HostError(f"{field or 'the document'}: must be {shape}, got {_label(value)}")
    elif isinstance(shape, ListOf):
        _check_list(value, shape, field)
    elif isinstance(shape, MapOf):
        if not isinstance(value, dict):
            raise HostError(f"{field or 'the document'}: must be an object (label: value), got {_label(value)}")
        for key, item in value.items():
            check(item, shape.item, f"{field}[{_label(key)}]")
    else:
        _check_fields(value, shape, field)


def _check_list(value, shape: ListOf, field: str) -> None:
    if not isinstance(value, list) or (shape.length is not None and len(value) != shape.length) \
            or len(value) < shape.min_length:
        size = f"{shape.length} " if shape.length is not None else ""
        raise HostError(f"{field or 'the document'}: must be a list of {size}values"
                        + (f" (at least {shape.min_length})" if shape.min_length else ""))
    for i, item in enumerate(value):
        check(item, shape.item, f"{field}[{i}]")


def _check_fields(value, shape: dict, field: str) -> None:
    if not isinstance(value, dict):
        raise HostError(f"{field or 'the document'}: must be an object, got {_label(value)}")
    for key, item_shape in shape.items():
        name = key.rstrip("?")
        where = f"{field}.{name}" if field else name
        if name in value:
            check(value[name], item_shape, where)
        elif not key.endswith("?"):
            raise HostError(f"{where}: missing")


def _check_frequency_grid(doc: dict) -> None:
    """Every controller's amplitudes on the first controller's frequencies (the report's columns)."""
    freq = doc["frequency"]
    first = next(iter(freq.values()), None)
    for label, f in freq.items():
        n = len(first["freqs_hz"])
        if len(f["freqs_hz"]) != n or any(len(row) != n for row in f["amplitude_deg"]):
            raise HostError(f"frequency[{_label(label)}]: must hold {n} frequencies and 3 x {n} amplitudes")


def _check_calibration_labels(doc: dict) -> None:
    """The rows the fidelity section looks up by the labels exist."""
    tables = {"prediction.staring": doc["prediction"]["staring"]}
    if doc.get("scale_fit"):
        tables["scale_fit.prediction"] = doc["scale_fit"]["prediction"]
    for table, rows in tables.items():
        for key in ("table1", "network"):
            if doc["labels"][key] not in rows:
                raise HostError(f"{table}: no row for labels.{key} {_label(doc['labels'][key])}")


def _check_gp_run(doc: dict) -> None:
    """A known law and start; a GP law's run carries its variance fractions (the baseline's are null)."""
    if doc["controller"] not in GP_CONTROLLERS:
        raise HostError(f"controller: expected one of {', '.join(GP_CONTROLLERS)}, got {_label(doc['controller'])}")
    if doc["start"] not in GP_STARTS:
        raise HostError(f"start: expected one of {', '.join(GP_STARTS)}, got {_label(doc['start'])}")
    if doc["controller"] != "gp-baseline":
        for key in ("var_fraction_first_60s", "var_fraction_last_60s"):
            if doc[key] is None:
                raise HostError(f"{key}: a GP law's run must give it, got null")


def read_basilisk(path: Path) -> dict:
    """crosscheck.json of `staregen basilisk --compare`, of either kind, checked (one line otherwise)."""
    what, writer = "Basilisk cross-check (crosscheck.json)", "staregen basilisk --compare"
    doc = read(path, what, {"kind": TEXT}, writer)
    shape = {"staring": BASILISK_STARING, "tanh": BASILISK_TANH}.get(doc["kind"])
    try:
        if shape is None:
            raise HostError(f"kind: expected 'staring' or 'tanh', got {_label(doc['kind'])}")
        check(doc, shape, "")
    except HostError as exc:
        raise HostError(f"{path}: not written by `{writer}`: {exc}") from None
    return doc


def _refuse_constant(name: str):
    raise ValueError(f"{name} is not JSON")


def read(path: Path, what: str, shape, writer: str) -> dict:
    """The JSON document at `path` (strict JSON, at most MAX_DOCUMENT_BYTES) with `shape`, or a
    one-line HostError naming the file (and the field)."""
    try:
        with open(path, "rb") as fh:
            data = fh.read(MAX_DOCUMENT_BYTES + 1)
    except OSError as exc:
        raise HostError(f"{path}: cannot read the {what} ({exc.strerror or exc})") from None
    if len(data) > MAX_DOCUMENT_BYTES:
        raise HostError(f"{path}: the {what} is larger than {MAX_DOCUMENT_BYTES >> 20} MiB")
    try:
        doc = json.loads(data, parse_constant=_refuse_constant)
    except (ValueError, RecursionError):
        raise HostError(f"{path}: the {what} is not valid JSON") from None
    try:
        check(doc, shape, "")
        if shape is EVALUATION:
            _check_frequency_grid(doc)
        if shape is CALIBRATION:
            _check_calibration_labels(doc)
        if shape is GP_RUN:
            _check_gp_run(doc)
        group = RBF_IN_LOOP if shape is RBF_RUN else GP_IN_LOOP if shape is GP_RUN else ()
        if 0 < sum(key in doc for key in group) < len(group):
            missing = next(key for key in group if key not in doc)
            raise HostError(f"{missing}: missing (a C-in-the-loop run has all of {', '.join(group)})")
    except HostError as exc:
        raise HostError(f"{path}: not written by `{writer}`: {exc}") from None
    return doc
