"""The model artifact: one versioned JSON file holding everything the flight C is generated from.

Layer sizes and activations, float32 weights stored exactly (hex-float strings), the mapminmax
settings of inputs and outputs as MATLAB computes them, the input envelope (paper 001 Table 2
by default), output names/units and metadata, sealed by the sha256 of the payload.
The schema is documented field by field in docs/artifact.md.

Public API (issue 3 item 6): `from_torch`, `from_arrays`, `random_artifact`, `load`,
`Artifact.save`.
"""
from __future__ import annotations

import hashlib
import json
import math
import os
import re
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Mapping, Sequence

import numpy as np

from codegen.errors import CodegenError
from codegen import atomic, reading
from codegen.values import DIGITS_TEXT, show

FORMAT = "staregen.mlp-artifact"
VERSION = 1
ACTIVATIONS = ("tansig", "purelin")

# MATLAB's mapminmax treats a row whose gain would exceed this as constant (see mapminmax_settings).
MATLAB_MAX_GAIN = 1e14

TABLE2_SOURCE = "paper 001 (staring imaging NN controller), section 5.2, Table 2"
TABLE2_NAMES = (
    "omega_d_x", "omega_d_y", "omega_d_z",
    "omega_dot_d_x", "omega_dot_d_y", "omega_dot_d_z",
    "phi_bd", "theta_bd", "psi_bd",
    "omega_e_x", "omega_e_y", "omega_e_z",
)
TABLE2_UNITS = ("deg/s",) * 3 + ("deg/s^2",) * 3 + ("deg",) * 3 + ("deg/s",) * 3
TABLE2_DESCRIPTIONS = (
    "desired angular velocity of S_d w.r.t. S_i, x component in body axes",
    "desired angular velocity of S_d w.r.t. S_i, y component in body axes",
    "desired angular velocity of S_d w.r.t. S_i, z component in body axes",
    "time derivative of the desired angular velocity, x component",
    "time derivative of the desired angular velocity, y component",
    "time derivative of the desired angular velocity, z component",
    "attitude error S_d -> S_b, 3-1-2 Euler angle phi (about x)",
    "attitude error S_d -> S_b, 3-1-2 Euler angle theta (about y)",
    "attitude error S_d -> S_b, 3-1-2 Euler angle psi (about z)",
    "angular velocity error omega_b - omega_d, x component in S_b",
    "angular velocity error omega_b - omega_d, y component in S_b",
    "angular velocity error omega_b - omega_d, z component in S_b",
)
TABLE2_MIN = (-0.1, -1.2, -0.05, -0.005, -0.015, -0.005, -0.02, -0.02, -0.02, -0.004, -0.004, -0.004)
TABLE2_MAX = (0.1, 0.0, 0.05, 0.005, 0.015, 0.005, 0.02, 0.02, 0.02, 0.004, 0.004, 0.004)

TORQUE_NAMES = ("M_cmd_x", "M_cmd_y", "M_cmd_z")
TORQUE_DESCRIPTIONS = tuple(f"commanded control torque, {a} component in S_b" for a in "xyz")


class ArtifactError(CodegenError):
    """A rejected artifact: names the offending field (JSON path) and the reason."""

    def __init__(self, field_path: str, reason: str, source: str | None = None):
        self.field_path = field_path
        self.reason = reason
        self.source = source
        prefix = f"{source}: " if source else ""
        super().__init__(f"{prefix}{field_path}: {reason}")


# ----------------------------------------------------------------------------- float encoding

def hex_float(value: float) -> str:
    """Exact, compact hex-float text of a float64 value (Python float.hex without trailing zeros)."""
    text = float(value).hex()
    if not math.isfinite(value):
        return text
    mantissa, exponent = text.split("p")
    if "." in mantissa:
        mantissa = mantissa.rstrip("0").rstrip(".")
    return f"{mantissa}p{exponent}"


# Text that the emitters copy into C comments: printable ASCII, bounded, with no sequence that could
# end the comment ("*/"), open a nested one ("/*"), form a trigraph ("??") or continue a line ("\\"
# at the end). The generator checks it again when it emits (codegen.cgen.comment).
COMMENT_TEXT = re.compile(r"[ -~]{0,200}")


def comment_text_problem(text) -> str | None:
    """Why `text` may not go into a C comment, or None if it may."""
    if not isinstance(text, str):
        return f"expected a string, got {type(text).__name__}"
    if not COMMENT_TEXT.fullmatch(text):
        return "must be printable ASCII of at most 200 characters (it goes into C comments)"
    for bad in ("*/", "/*", "??"):
        if bad in text:
            return f"must not contain {bad!r} (it goes into C comments)"
    if text.endswith("\\"):
        return "must not end in a backslash (it goes into C comments)"
    return None


def is_float32_exact(value: float) -> bool:
    """True if the float64 value survives a round trip through float32 (NaN counts as exact)."""
    with np.errstate(over="ignore"):
        back = float(np.float32(value))
    return back == value or (math.isnan(value) and math.isnan(back))


# ----------------------------------------------------------------------------- mapminmax

@dataclass(frozen=True)
class MapMinMax:
    """MATLAB mapminmax settings of one side of the network; the flight C has them folded into the
    layers (codegen/units/network/fold.py), the float64 reference applies them as written.

    y = (x - xoffset) * gain + ymin,   x = (y - ymin) / gain + xoffset.
    xmin/xmax are the raw data ranges (float64, as given); xoffset/gain are float32.
    """

    xmin: np.ndarray
    xmax: np.ndarray
    ymin: np.float32
    ymax: np.float32
    xoffset: np.ndarray
    gain: np.ndarray


def matlab_mapminmax64(xmin, xmax, ymin: float = -1.0, ymax: float = 1.0) -> tuple[np.ndarray, np.ndarray]:
    """MATLAB's (xoffset, gain) in float64, including its rule for constant rows.

    gain = (ymax - ymin) / (xmax - xmin), xoffset = xmin; a row whose range is zero or
    non-finite, or whose gain exceeds 1e14 in magnitude, passes through unchanged:
    gain = 1, xoffset = ymin (MATLAB mapminmax settings, NNT 7+).
    """
    xmin = np.asarray(xmin, dtype=np.float64)
    xmax = np.asarray(xmax, dtype=np.float64)
    with np.errstate(over="ignore", divide="ignore", invalid="ignore"):
        xrange = xmax - xmin
        gain = (float(ymax) - float(ymin)) / xrange
    fix = (np.abs(gain) > MATLAB_MAX_GAIN) | ~np.isfinite(xrange) | (xrange == 0)
    xoffset = np.where(fix, float(ymin), xmin)
    gain = np.where(fix, 1.0, gain)
    return xoffset, gain


def mapminmax_settings(xmin, xmax, ymin: float = -1.0, ymax: float = 1.0) -> MapMinMax:
    """Settings for raw ranges [xmin, xmax] mapped to [ymin, ymax]; float32 rounded to nearest."""
    xmin = np.array(xmin, dtype=np.float64).reshape(-1)
    xmax = np.array(xmax, dtype=np.float64).reshape(-1)
    xoffset, gain = matlab_mapminmax64(xmin, xmax, ymin, ymax)
    with np.errstate(over="ignore", under="ignore"):
        return MapMinMax(
            xmin=xmin, xmax=xmax, ymin=np.float32(ymin), ymax=np.float32(ymax),
            xoffset=xoffset.astype(np.float32), gain=gain.astype(np.float32),
        )


# ----------------------------------------------------------------------------- envelope, outputs

@dataclass(frozen=True)
class Envelope:
    """Input box inside which the network flies; bounds are float32 (the flight check compares float32)."""

    names: tuple[str, ...]
    units: tuple[str, ...]
    descriptions: tuple[str, ...]
    min: np.ndarray
    max: np.ndarray
    source: str


@dataclass(frozen=True)
class OutputSpec:
    names: tuple[str, ...]
    units: tuple[str, ...]
    descriptions: tuple[str, ...]


def table2_envelope() -> Envelope:
    """Paper 001 Table 2, rounded to the nearest float32."""
    return Envelope(
        names=TABLE2_NAMES, units=TABLE2_UNITS, descriptions=TABLE2_DESCRIPTIONS,
        min=np.array(TABLE2_MIN, dtype=np.float32), max=np.array(TABLE2_MAX, dtype=np.float32),
        source=TABLE2_SOURCE,
    )


def synthetic_envelope(n_in: int, rng: np.random.Generator) -> Envelope:
    """A random box for artifacts whose inputs are not the paper's 12 (centres and spans vary by decades)."""
    centre = rng.uniform(-10.0, 10.0, n_in)
    half_span = 10.0 ** rng.uniform(-3.0, 1.0, n_in)
    return Envelope(
        names=tuple(f"x{i}" for i in range(n_in)), units=("1",) * n_in,
        descriptions=tuple(f"synthetic input {i}" for i in range(n_in)),
        min=(centre - half_span).astype(np.float32), max=(centre + half_span).astype(np.float32),
        source="synthetic (random artifact)",
    )


def default_outputs(n_in: int, n_out: int) -> OutputSpec:
    if n_in == 12 and n_out == 3:
        return OutputSpec(TORQUE_NAMES, ("N*m",) * 3, TORQUE_DESCRIPTIONS)
    return OutputSpec(tuple(f"y{k}" for k in range(n_out)), ("1",) * n_out,
                      tuple(f"output {k}" for k in range(n_out)))


def envelope_from(spec, n_in: int, x_min, x_max) -> Envelope:
    """The envelope argument of from_torch/from_arrays: None, an Envelope, a mapping or (min, max)."""
    if isinstance(spec, Envelope):
        return spec
    if spec is None:
        if n_in == 12:
            return table2_envelope()
        spec = {"min": x_min, "max": x_max, "source": "training input range (x_min, x_max)"}
    if isinstance(spec, (tuple, list)) and len(spec) == 2:
        spec = {"min": spec[0], "max": spec[1]}
    if not isinstance(spec, Mapping):
        raise ArtifactError("envelope", f"expected None, Envelope, a mapping or (min, max), got {type(spec).__name__}")
    for key in ("min", "max"):
        if key not in spec:
            raise ArtifactError(f"envelope.{key}", "missing field")
    names = tuple(spec.get("names", TABLE2_NAMES if n_in == 12 else tuple(f"x{i}" for i in range(n_in))))
    units = tuple(spec.get("units", TABLE2_UNITS if n_in == 12 else ("1",) * n_in))
    descriptions = tuple(spec.get("descriptions", TABLE2_DESCRIPTIONS if n_in == 12 else names))
    with np.errstate(over="ignore"):
        lo = np.asarray(spec["min"], dtype=np.float64).astype(np.float32).reshape(-1)
        hi = np.asarray(spec["max"], dtype=np.float64).astype(np.float32).reshape(-1)
    return Envelope(names, units, descriptions, lo, hi, str(spec.get("source", "user supplied")))


# ----------------------------------------------------------------------------- the artifact

@dataclass(frozen=True)
class Artifact:
    """A validated n_in-n_hidden-n_out tansig/purelin network with its normalisation and envelope.

    Weights are row-major W[out][in] float32: W1 (n_hidden, n_in), W2 (n_out, n_hidden).
    Construction validates everything the loader does except the sha256 seal.
    """

    W1: np.ndarray
    b1: np.ndarray
    W2: np.ndarray
    b2: np.ndarray
    input_map: MapMinMax
    output_map: MapMinMax
    envelope: Envelope
    outputs: OutputSpec
    metadata: dict = field(default_factory=dict)

    def __post_init__(self):
        validate(self)

    @property
    def n_in(self) -> int:
        return int(self.W1.shape[1])

    @property
    def n_hidden(self) -> int:
        return int(self.W1.shape[0])

    @property
    def n_out(self) -> int:
        return int(self.W2.shape[0])

    @property
    def sizes(self) -> tuple[int, int, int]:
        return (self.n_in, self.n_hidden, self.n_out)

    @property
    def shape_text(self) -> str:
        return "-".join(str(s) for s in self.sizes)

    def payload(self) -> dict:
        return _payload_of(self)

    @property
    def sha256(self) -> str:
        return payload_sha256(self.payload())

    def document(self) -> dict:
        return sealed(FORMAT, VERSION, self.payload())

    def to_json(self) -> str:
        return pretty_json(self.document()) + "\n"

    def save(self, path: str | os.PathLike) -> Path:
        """Write atomically (a killed run leaves the old file or the new one)."""
        return atomic.write_text(path, self.to_json())


def payload_sha256(payload: Mapping) -> str:
    """sha256 of the canonical payload text: sorted keys, no whitespace, ASCII."""
    canonical = json.dumps(payload, sort_keys=True, separators=(",", ":"), ensure_ascii=True, allow_nan=False)
    return hashlib.sha256(canonical.encode("ascii")).hexdigest()


def _hex_list(values) -> list[str]:
    return [hex_float(float(v)) for v in np.asarray(values).reshape(-1)]


def _map_payload(m: MapMinMax) -> dict:
    return {
        "xmin": _hex_list(m.xmin), "xmax": _hex_list(m.xmax),
        "ymin": hex_float(float(m.ymin)), "ymax": hex_float(float(m.ymax)),
        "xoffset": _hex_list(m.xoffset), "gain": _hex_list(m.gain),
    }


def _layer_payload(W: np.ndarray, b: np.ndarray) -> dict:
    return {"weights": [_hex_list(row) for row in W], "bias": _hex_list(b)}


def _payload_of(a: Artifact) -> dict:
    env = a.envelope
    return {
        "network": {
            "sizes": list(a.sizes),
            "activations": list(ACTIVATIONS),
            "layers": [_layer_payload(a.W1, a.b1), _layer_payload(a.W2, a.b2)],
        },
        "normalisation": {"input": _map_payload(a.input_map), "output": _map_payload(a.output_map)},
        "envelope": {
            "source": env.source, "names": list(env.names), "units": list(env.units),
            "descriptions": list(env.descriptions), "min": _hex_list(env.min), "max": _hex_list(env.max),
        },
        "outputs": {"names": list(a.outputs.names), "units": list(a.outputs.units),
                    "descriptions": list(a.outputs.descriptions)},
        "metadata": dict(a.metadata),
    }


def pretty_json(obj, indent: int = 0) -> str:
    """JSON with one line per innermost list of scalars (a weight row stays on one line)."""
    pad, inner = " " * indent, " " * (indent + 2)
    if isinstance(obj, dict):
        if not obj:
            return "{}"
        items = [f"{inner}{json.dumps(k)}: {pretty_json(v, indent + 2)}" for k, v in obj.items()]
        return "{\n" + ",\n".join(items) + "\n" + pad + "}"
    if isinstance(obj, list) and any(isinstance(v, (list, dict)) for v in obj):
        items = [f"{inner}{pretty_json(v, indent + 2)}" for v in obj]
        return "[\n" + ",\n".join(items) + "\n" + pad + "]"
    return json.dumps(obj, allow_nan=False)


# ----------------------------------------------------------------------------- semantic validation

NETWORK = "payload.network"
NORMALISATION = "payload.normalisation"
ENVELOPE = "payload.envelope"


def validate(a: Artifact) -> None:
    """Every semantic rule of the schema; raises ArtifactError(field path, reason)."""
    _check_layer_shapes(a)
    for k, (W, b) in enumerate(((a.W1, a.b1), (a.W2, a.b2))):
        _check_float32_finite(W, f"{NETWORK}.layers[{k}].weights")
        _check_float32_finite(b, f"{NETWORK}.layers[{k}].bias")
    _check_map(a.input_map, a.n_in, f"{NORMALISATION}.input")
    _check_map(a.output_map, a.n_out, f"{NORMALISATION}.output")
    _check_envelope(a.envelope, a.n_in)
    _check_labels(a.outputs.names, a.outputs.units, a.outputs.descriptions, a.n_out, "payload.outputs")
    _check_metadata(a.metadata)


def _shape(arr) -> str:
    return "x".join(str(s) for s in np.shape(arr)) or "scalar"


def _check_layer_shapes(a: Artifact) -> None:
    if np.ndim(a.W1) != 2 or np.ndim(a.W2) != 2:
        raise ArtifactError(f"{NETWORK}.layers", f"weights must be 2-D matrices, got {_shape(a.W1)} and {_shape(a.W2)}")
    n_hidden, n_in = a.W1.shape
    n_out = a.W2.shape[0]
    if min(n_in, n_hidden, n_out) < 1:
        raise ArtifactError(f"{NETWORK}.sizes", f"every layer needs at least one neuron, got {n_in}-{n_hidden}-{n_out}")
    expected = {
        f"{NETWORK}.layers[0].bias": ((n_hidden,), a.b1, "n_hidden"),
        f"{NETWORK}.layers[1].weights": ((n_out, n_hidden), a.W2, "n_out x n_hidden"),
        f"{NETWORK}.layers[1].bias": ((n_out,), a.b2, "n_out"),
    }
    for path, (shape, arr, meaning) in expected.items():
        if tuple(np.shape(arr)) != shape:
            want = "x".join(map(str, shape))
            raise ArtifactError(path, f"shape mismatch: expected {want} ({meaning}), got {_shape(arr)}")


def _first_bad(mask: np.ndarray) -> str:
    index = np.argwhere(mask)[0]
    return "".join(f"[{i}]" for i in index)


def _check_float32_finite(arr, path: str) -> None:
    arr = np.asarray(arr)
    if arr.dtype != np.float32:
        raise ArtifactError(path, f"expected float32 values, got dtype {arr.dtype}")
    bad = ~np.isfinite(arr)
    if bad.any():
        where = _first_bad(bad)
        raise ArtifactError(f"{path}{where}", f"non-finite value {float(arr[tuple(np.argwhere(bad)[0])])}")


def _check_map(m: MapMinMax, n: int, path: str) -> None:
    for name in ("xmin", "xmax", "xoffset", "gain"):
        arr = np.asarray(getattr(m, name))
        if arr.shape != (n,):
            raise ArtifactError(f"{path}.{name}", f"shape mismatch: expected {n} values, got {_shape(arr)}")
    for name in ("xmin", "xmax"):
        bad = ~np.isfinite(getattr(m, name))
        if bad.any():
            raise ArtifactError(f"{path}.{name}{_first_bad(bad)}", "non-finite data range")
    bad = m.xmin > m.xmax
    if bad.any():
        i = int(np.argwhere(bad)[0][0])
        raise ArtifactError(f"{path}.xmin[{i}]", f"xmin {float(m.xmin[i])!r} > xmax {float(m.xmax[i])!r}")
    if not (np.isfinite(m.ymin) and np.isfinite(m.ymax) and m.ymin < m.ymax):
        raise ArtifactError(f"{path}.ymin", f"mapped range needs finite ymin < ymax, got [{m.ymin}, {m.ymax}]")
    _check_float32_finite(m.xoffset, f"{path}.xoffset")
    _check_gain(m.gain, f"{path}.gain")
    _check_matlab_consistent(m, path)


def _check_gain(gain, path: str) -> None:
    gain = np.asarray(gain)
    if gain.dtype != np.float32:
        raise ArtifactError(path, f"expected float32 values, got dtype {gain.dtype}")
    bad = ~np.isfinite(gain) | (gain == 0)
    if bad.any():
        i = int(np.argwhere(bad)[0][0])
        raise ArtifactError(f"{path}[{i}]", f"gain must be finite and non-zero, got {float(gain[i])}")


def _check_matlab_consistent(m: MapMinMax, path: str) -> None:
    """xoffset and gain must be the float32 of what MATLAB's mapminmax computes from the ranges."""
    expected = mapminmax_settings(m.xmin, m.xmax, float(m.ymin), float(m.ymax))
    for name in ("xoffset", "gain"):
        got, want = getattr(m, name), getattr(expected, name)
        bad = got.view(np.uint32) != want.view(np.uint32)
        if bad.any():
            i = int(np.argwhere(bad)[0][0])
            raise ArtifactError(
                f"{path}.{name}[{i}]",
                f"{hex_float(float(got[i]))} is not MATLAB's mapminmax {name} for "
                f"[xmin, xmax] = [{float(m.xmin[i])!r}, {float(m.xmax[i])!r}] (expected {hex_float(float(want[i]))})")


def _check_labels(names, units, descriptions, n: int, path: str) -> None:
    for key, seq in (("names", names), ("units", units), ("descriptions", descriptions)):
        if len(seq) != n:
            raise ArtifactError(f"{path}.{key}", f"shape mismatch: expected {n} entries, got {len(seq)}")
        for i, s in enumerate(seq):
            problem = comment_text_problem(s)
            if problem:
                raise ArtifactError(f"{path}.{key}[{i}]", problem)
    for i, s in enumerate(names):
        if not re.fullmatch(r"[A-Za-z_][A-Za-z0-9_]*", s):
            raise ArtifactError(f"{path}.names[{i}]", f"{s!r} is not an identifier")


def _check_envelope(env: Envelope, n_in: int) -> None:
    _check_labels(env.names, env.units, env.descriptions, n_in, ENVELOPE)
    problem = comment_text_problem(env.source)
    if problem:
        raise ArtifactError(f"{ENVELOPE}.source", problem)
    for name in ("min", "max"):
        arr = np.asarray(getattr(env, name))
        if arr.shape != (n_in,):
            raise ArtifactError(f"{ENVELOPE}.{name}", f"shape mismatch: expected {n_in} values, got {_shape(arr)}")
        _check_float32_finite(arr, f"{ENVELOPE}.{name}")
    bad = ~(env.min < env.max)
    if bad.any():
        i = int(np.argwhere(bad)[0][0])
        raise ArtifactError(f"{ENVELOPE}.min[{i}]",
                            f"envelope min {float(env.min[i])!r} must be < max {float(env.max[i])!r}")


METADATA_TYPES = {
    "creator": (str,),
    "seed": (int, type(None)),
    "dataset_sha256": (str, type(None)),
    "test_mse": (float, int, type(None)),
}


def _check_metadata(meta: Mapping) -> None:
    if not isinstance(meta, Mapping):
        raise ArtifactError("payload.metadata", f"expected an object, got {type(meta).__name__}")
    for key, types in METADATA_TYPES.items():
        if key not in meta:
            raise ArtifactError(f"payload.metadata.{key}", "missing field")
        value = meta[key]
        if isinstance(value, bool) or not isinstance(value, types):
            allowed = " or ".join("null" if t is type(None) else t.__name__ for t in types)
            raise ArtifactError(f"payload.metadata.{key}", f"expected {allowed}, got {type(value).__name__}")
    problem = comment_text_problem(meta["creator"])
    if problem:
        raise ArtifactError("payload.metadata.creator", problem)
    mse = meta["test_mse"]
    if mse is not None and not (math.isfinite(mse) and mse >= 0):
        raise ArtifactError("payload.metadata.test_mse", f"must be a finite value >= 0, got {mse!r}")
    sha = meta["dataset_sha256"]
    if sha is not None and not re.fullmatch(r"[0-9a-f]{64}", sha):
        raise ArtifactError("payload.metadata.dataset_sha256", "expected 64 lowercase hex digits")
    try:
        json.dumps(dict(meta), allow_nan=False)
    except (TypeError, ValueError) as exc:
        raise ArtifactError("payload.metadata", f"not JSON-serialisable: {exc}") from None


# ----------------------------------------------------------------------------- constructors

def default_metadata(**overrides) -> dict:
    meta = {"creator": "staregen", "seed": None, "dataset_sha256": None, "test_mse": None}
    meta.update(overrides)
    return meta


def _as_float32(values, path: str) -> np.ndarray:
    arr = np.asarray(values)
    if not np.issubdtype(arr.dtype, np.number):
        raise ArtifactError(path, f"expected numbers, got dtype {arr.dtype}")
    with np.errstate(over="ignore"):
        return arr.astype(np.float32)


def from_arrays(W1, b1, W2, b2, x_min, x_max, y_min, y_max, envelope=None, metadata=None,
                outputs: OutputSpec | None = None) -> Artifact:
    """An artifact from plain arrays: W1 (n_hidden, n_in), b1, W2 (n_out, n_hidden), b2.

    x_min/x_max and y_min/y_max are the raw-unit data ranges of inputs and outputs; they are
    mapped to [-1, 1] as MATLAB's mapminmax does. Weights are rounded to float32.
    """
    W1 = _as_float32(W1, f"{NETWORK}.layers[0].weights")
    W2 = _as_float32(W2, f"{NETWORK}.layers[1].weights")
    n_in = W1.shape[1] if W1.ndim == 2 else 0
    n_out = W2.shape[0] if W2.ndim == 2 else 0
    return Artifact(
        W1=W1, b1=_as_float32(b1, f"{NETWORK}.layers[0].bias"),
        W2=W2, b2=_as_float32(b2, f"{NETWORK}.layers[1].bias"),
        input_map=mapminmax_settings(x_min, x_max),
        output_map=mapminmax_settings(y_min, y_max),
        envelope=envelope_from(envelope, n_in, x_min, x_max),
        outputs=outputs or default_outputs(n_in, n_out),
        metadata=default_metadata(**(metadata or {})),
    )


def from_torch(model, x_min, x_max, y_min, y_max, envelope=None, metadata=None) -> Artifact:
    """An artifact from a torch nn.Sequential(Linear, Tanh, Linear) and raw-unit data ranges."""
    import torch

    layers = list(model.children()) if isinstance(model, torch.nn.Sequential) else []
    kinds = [type(m).__name__ for m in layers]
    if kinds != ["Linear", "Tanh", "Linear"]:
        got = kinds if layers else type(model).__name__
        raise ArtifactError("model", f"expected nn.Sequential(Linear, Tanh, Linear), got {got}")
    first, last = layers[0], layers[2]
    if first.bias is None or last.bias is None:
        raise ArtifactError("model", "both Linear layers need a bias")
    meta = {"creator": "staregen from_torch", **(metadata or {})}
    return from_arrays(_tensor64(first.weight), _tensor64(first.bias), _tensor64(last.weight), _tensor64(last.bias),
                       x_min, x_max, y_min, y_max, envelope=envelope, metadata=meta)


def _tensor64(t) -> np.ndarray:
    """A torch parameter as float64 numpy (exact for float32/float16 tensors; rounded to float32 later)."""
    import torch

    return t.detach().cpu().to(torch.float64).numpy()


def parse_shape(text: str) -> tuple[int, int, int]:
    """'12-40-3' -> (12, 40, 3), refused before anything is allocated when no artifact may hold it."""
    parts = text.split("-")
    if len(parts) != 3 or not all(DIGITS_TEXT.fullmatch(p) and len(p) <= 6 and 0 < int(p) <= MAX_LAYER_SIZE for p in parts):
        raise CodegenError(f"--shape: expected N_IN-N_HIDDEN-N_OUT with integers in [1, {MAX_LAYER_SIZE}] "
                           f"(e.g. 12-40-3), got {text[:40]!r}")
    shape = tuple(int(p) for p in parts)
    problem = shape_problem(shape)
    if problem:
        raise CodegenError(f"--shape: {text}: {problem}")
    return shape  # type: ignore[return-value]


# Bigger layers cannot be flight code on the STM32F417 (12-10000-3 is 640 KB of weights of 1 MB flash).
MAX_LAYER_SIZE = 10_000
# What an artifact may hold: at about 16 bytes per value as written (a float32 hex float, its quotes
# and separator), a MAX_FILE_BYTES file holds about 4.2 million weights and biases.
MAX_PARAMETERS = reading.MAX_FILE_BYTES // 16


def n_parameters(shape: Sequence[int]) -> int:
    n_in, n_hidden, n_out = shape
    return n_hidden * (n_in + 1) + n_out * (n_hidden + 1)


def shape_problem(shape: Sequence[int]) -> str | None:
    """None, or why no artifact may hold a network of this (n_in, n_hidden, n_out)."""
    if n_parameters(shape) > MAX_PARAMETERS:
        return (f"{n_parameters(shape):,} weights and biases, more than the {MAX_PARAMETERS:,} "
                f"an artifact may hold (its file is at most {MAX_FILE_BYTES >> 20} MiB)")
    return None


def random_artifact(shape: Sequence[int] = (12, 40, 3), seed: int = 0) -> Artifact:
    """A randomly initialised network (no training), deterministic in `seed`.

    12 inputs get the Table 2 envelope and data ranges; other shapes a synthetic envelope.
    Weights are large enough that hidden pre-activations reach tanh saturation.
    """
    n_in, n_hidden, n_out = (int(s) for s in shape)
    problem = shape_problem((n_in, n_hidden, n_out))
    if problem:     # before allocating the weights
        raise CodegenError(f"shape {n_in}-{n_hidden}-{n_out}: {problem}")
    rng = np.random.default_rng(seed)
    W1 = rng.uniform(-1.0, 1.0, (n_hidden, n_in))
    b1 = rng.uniform(-1.0, 1.0, n_hidden)
    W2 = rng.uniform(-1.0, 1.0, (n_out, n_hidden)) / math.sqrt(n_hidden)
    b2 = rng.uniform(-0.1, 0.1, n_out)
    env = table2_envelope() if n_in == 12 else synthetic_envelope(n_in, rng)
    y_half = 10.0 ** rng.uniform(-2.0, 0.0, n_out)
    y_centre = rng.uniform(-0.1, 0.1, n_out) * y_half
    meta = default_metadata(creator="staregen artifact random", seed=int(seed))
    return from_arrays(W1, b1, W2, b2, env.min.astype(np.float64), env.max.astype(np.float64),
                       y_centre - y_half, y_centre + y_half, envelope=env, metadata=meta)


# ----------------------------------------------------------------------------- loader

class DocumentReader:
    """Walks a sealed JSON document (the network artifact, the GP artifact); every complaint names the field path."""

    def __init__(self, source: str | None):
        self.source = source

    def fail(self, path: str, reason: str):
        raise ArtifactError(path, reason, self.source)

    def obj(self, value, path: str, keys: Sequence[str], open_ended: bool = False) -> dict:
        if not isinstance(value, dict):
            self.fail(path or "(document)", f"expected an object, got {_json_type(value)}")
        for key in keys:
            if key not in value:
                self.fail(f"{path}.{key}" if path else key, "missing field")
        extra = sorted(set(value) - set(keys))
        if extra and not open_ended:
            self.fail(f"{path}.{extra[0]}" if path else extra[0], "unknown field")
        return value

    def list(self, value, path: str, n: int | None = None) -> list:
        if not isinstance(value, list):
            self.fail(path, f"expected a list, got {_json_type(value)}")
        if n is not None and len(value) != n:
            self.fail(path, f"shape mismatch: expected {n} entries, got {len(value)}")
        return value

    def strings(self, value, path: str, n: int) -> tuple[str, ...]:
        items = self.list(value, path, n)
        for i, s in enumerate(items):
            if not isinstance(s, str):
                self.fail(f"{path}[{i}]", f"expected a string, got {_json_type(s)}")
        return tuple(items)

    def real(self, value, path: str, float32: bool) -> float:
        if not isinstance(value, str):
            self.fail(path, f"expected a hex-float string such as \"0x1.99999ap-4\", got {_json_type(value)}")
        try:
            x = float.fromhex(value)
        except (ValueError, OverflowError):
            self.fail(path, f"{_clip(value)!r} is not a hex float within float64")
        if hex_float(x) != value:
            self.fail(path, f"{_clip(value)!r} is not in canonical form: write {hex_float(x)!r} "
                            "(Python float.hex without trailing zeros; the seal hashes this text)")
        if float32 and not is_float32_exact(x):
            self.fail(path, f"{value} is not exactly representable in float32")
        return x

    def vector(self, value, path: str, n: int, float32: bool = True) -> np.ndarray:
        items = self.list(value, path, n)
        xs = [self.real(v, f"{path}[{i}]", float32) for i, v in enumerate(items)]
        with np.errstate(over="ignore"):
            return np.array(xs, dtype=np.float32 if float32 else np.float64)

    def matrix(self, value, path: str, rows: int, cols: int, meaning: str) -> np.ndarray:
        items = self.list(value, path)
        if len(items) != rows:
            self.fail(path, f"shape mismatch: expected {rows} rows ({meaning}), got {len(items)}")
        return np.stack([self.vector(r, f"{path}[{i}]", cols) for i, r in enumerate(items)]).reshape(rows, cols)


def _clip(text: str, n: int = 40) -> str:
    return text if len(text) <= n else text[:n - 3] + "..."


def _json_type(value) -> str:
    return {dict: "an object", list: "a list", str: "a string", bool: "a boolean",
            int: "a number", float: "a number", type(None): "null"}.get(type(value), type(value).__name__)


def _read_sizes(r: DocumentReader, network: dict) -> tuple[int, int, int]:
    sizes = r.list(network["sizes"], f"{NETWORK}.sizes")
    if len(sizes) != 3:
        r.fail(f"{NETWORK}.sizes", f"expected 3 sizes [n_in, n_hidden, n_out], got {len(sizes)}")
    for i, s in enumerate(sizes):
        if isinstance(s, bool) or not isinstance(s, int) or s < 1:
            r.fail(f"{NETWORK}.sizes[{i}]", f"expected a positive integer, got {_clip(repr(s))}")
    problem = shape_problem(sizes)
    if problem:
        r.fail(f"{NETWORK}.sizes", problem)
    acts = r.strings(network["activations"], f"{NETWORK}.activations", 2)
    if acts != ACTIVATIONS:
        r.fail(f"{NETWORK}.activations", f"expected {list(ACTIVATIONS)}, got {list(acts)}")
    return tuple(sizes)  # type: ignore[return-value]


def _read_layer(r: DocumentReader, value, k: int, rows: int, cols: int, meaning: str) -> tuple[np.ndarray, np.ndarray]:
    path = f"{NETWORK}.layers[{k}]"
    layer = r.obj(value, path, ("weights", "bias"))
    return (r.matrix(layer["weights"], f"{path}.weights", rows, cols, meaning),
            r.vector(layer["bias"], f"{path}.bias", rows))


def _read_map(r: DocumentReader, value, path: str, n: int) -> MapMinMax:
    m = r.obj(value, path, ("xmin", "xmax", "ymin", "ymax", "xoffset", "gain"))
    return MapMinMax(
        xmin=r.vector(m["xmin"], f"{path}.xmin", n, float32=False),
        xmax=r.vector(m["xmax"], f"{path}.xmax", n, float32=False),
        ymin=np.float32(r.real(m["ymin"], f"{path}.ymin", True)),
        ymax=np.float32(r.real(m["ymax"], f"{path}.ymax", True)),
        xoffset=r.vector(m["xoffset"], f"{path}.xoffset", n),
        gain=r.vector(m["gain"], f"{path}.gain", n),
    )


def _read_envelope(r: DocumentReader, value, n_in: int) -> Envelope:
    e = r.obj(value, ENVELOPE, ("source", "names", "units", "descriptions", "min", "max"))
    if not isinstance(e["source"], str):
        r.fail(f"{ENVELOPE}.source", f"expected a string, got {_json_type(e['source'])}")
    return Envelope(
        names=r.strings(e["names"], f"{ENVELOPE}.names", n_in),
        units=r.strings(e["units"], f"{ENVELOPE}.units", n_in),
        descriptions=r.strings(e["descriptions"], f"{ENVELOPE}.descriptions", n_in),
        min=r.vector(e["min"], f"{ENVELOPE}.min", n_in), max=r.vector(e["max"], f"{ENVELOPE}.max", n_in),
        source=e["source"],
    )


def _read_outputs(r: DocumentReader, value, n_out: int) -> OutputSpec:
    o = r.obj(value, "payload.outputs", ("names", "units", "descriptions"))
    return OutputSpec(*(r.strings(o[k], f"payload.outputs.{k}", n_out) for k in ("names", "units", "descriptions")))


def read_envelope(r: DocumentReader, doc: Any, fmt: str, version: int, payload_keys: tuple[str, ...]) -> dict:
    """The sealed document's envelope (format, version, sha256, payload) checked; returns the payload
    object with exactly payload_keys (the seal itself is checked last, by check_seal)."""
    r.obj(doc, "", ("format", "version", "sha256", "payload"))
    if doc["format"] != fmt:
        r.fail("format", f"expected {fmt!r}, got {show(doc['format'], 60)}")
    if type(doc["version"]) is not int or doc["version"] != version:
        r.fail("version", f"unsupported artifact version {show(doc['version'], 20)} (this staregen reads version {version})")
    return r.obj(doc["payload"], "payload", payload_keys)


def from_document(doc: Any, source: str | None = None) -> Artifact:
    """Validate a parsed JSON document and build the Artifact; the sha256 seal is checked last."""
    r = DocumentReader(source)
    payload = read_envelope(r, doc, FORMAT, VERSION, ("network", "normalisation", "envelope", "outputs", "metadata"))
    network = r.obj(payload["network"], NETWORK, ("sizes", "activations", "layers"))
    n_in, n_hidden, n_out = _read_sizes(r, network)
    layers = r.list(network["layers"], f"{NETWORK}.layers", 2)
    W1, b1 = _read_layer(r, layers[0], 0, n_hidden, n_in, "n_hidden x n_in")
    W2, b2 = _read_layer(r, layers[1], 1, n_out, n_hidden, "n_out x n_hidden")
    norm = r.obj(payload["normalisation"], NORMALISATION, ("input", "output"))
    metadata = r.obj(payload["metadata"], "payload.metadata", (), open_ended=True)
    try:
        artifact = Artifact(
            W1=W1, b1=b1, W2=W2, b2=b2,
            input_map=_read_map(r, norm["input"], f"{NORMALISATION}.input", n_in),
            output_map=_read_map(r, norm["output"], f"{NORMALISATION}.output", n_out),
            envelope=_read_envelope(r, payload["envelope"], n_in),
            outputs=_read_outputs(r, payload["outputs"], n_out),
            metadata=dict(metadata),
        )
    except ArtifactError as exc:
        raise ArtifactError(exc.field_path, exc.reason, source) from None
    check_seal(r, doc)
    if artifact.sha256 != doc["sha256"]:   # every value canonical, so this holds unless a rule is missing
        r.fail("payload", "not in canonical form: its values re-serialise to another text than the sealed one")
    return artifact


def sealed(format_: str, version: int, payload: dict) -> dict:
    """A document of any sealed artifact format: its payload and the sha256 that seals it."""
    return {"format": format_, "version": version, "sha256": payload_sha256(payload), "payload": payload}


def seal_problem(doc: dict) -> str | None:
    """Why a document's stated sha256 does not seal its payload (None when it does)."""
    stated = doc["sha256"]
    if not isinstance(stated, str) or not re.fullmatch(r"[0-9a-f]{64}", stated):
        return f"expected 64 lowercase hex digits, got {str(stated)[:70]!r}"
    actual = payload_sha256(doc["payload"])
    if actual != stated:
        return (f"mismatch: the payload hashes to {actual}, the file states {stated} "
                "(payload modified after it was sealed)")
    return None


def check_seal(r: DocumentReader, doc: dict) -> None:
    problem = seal_problem(doc)
    if problem:
        r.fail("sha256", problem)


def read_document(path: str | os.PathLike):
    """A sealed JSON file's document (any artifact format): size-capped by the bytes read, a
    regular file, UTF-8, strict JSON."""
    try:
        text = reading.read_bytes(path, MAX_FILE_BYTES).decode("utf-8")
    except reading.InputFileError as exc:
        raise ArtifactError("file", str(exc).removeprefix(f"{path}: "), str(path)) from None
    except UnicodeDecodeError as exc:
        raise ArtifactError("file", f"cannot read: {exc}", str(path)) from None
    return parse_json(text, str(path))


def load(path: str | os.PathLike) -> Artifact:
    """Read and validate an artifact file; any problem raises ArtifactError naming the field."""
    return from_document(read_document(path), str(path))


MAX_FILE_BYTES = reading.MAX_FILE_BYTES
MAX_DEPTH = reading.MAX_JSON_DEPTH


def parse_json(text: str, source: str | None = None):
    """Strict JSON: no NaN/Infinity constants, no duplicate keys, at most MAX_DEPTH levels of nesting."""
    try:
        return reading.parse_json(text)
    except ValueError as exc:
        raise ArtifactError("file", f"not valid JSON: {str(exc).splitlines()[0] if str(exc) else 'too deep'}",
                            source) from None


def summary(a: Artifact) -> str:
    """Two lines for `staregen artifact check`."""
    meta = a.metadata
    return (f"{a.shape_text} tansig/purelin, sha256 {a.sha256}\n"
            f"envelope: {a.envelope.source}; outputs: {', '.join(f'{n} [{u}]' for n, u in zip(a.outputs.names, a.outputs.units))}; "
            f"creator: {meta.get('creator')}, seed: {meta.get('seed')}, test_mse: {meta.get('test_mse')}")
