"""Parameter file of paper 004's GP takeover law (docs/gp-takeover.md sections 5 and 11) and its one reader.

The law's file names the trained GP artifact (a sealed `staregen.gp-artifact`, path relative to the
parameter file's folder) and the law's own constants: the gain bounds k1 <= k1_bar, k2 <= k2_bar, the
torque limit and the prior inertia J_s the gyroscopic term uses. Lives in codegen because the C
generator bakes the values in and codegen must not import host; the host law
(host/control/takeover_laws.py) is built from the same object. Errors are one-line `GpParamsError`s.

    artifact   = "gp_takeover_m20.json"     # relative to this file's folder
    k1 = 4.0                                # N*m,        K1(s) = k1 + (k1_bar - k1) s
    k1_bar = 16.0
    k2 = 72.0                               # N*m*s/rad,  K2(s) = k2 + (k2_bar - k2) s
    k2_bar = 144.0
    torque_max = 1.0                        # N*m per axis
    inertia = [[...], [...], [...]]         # kg*m^2, J_s, symmetric positive definite
"""
from __future__ import annotations

import hashlib
import json
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from codegen import values
from codegen.artifact import ArtifactError
from codegen.errors import CodegenError
from codegen.units.gp import artifact as gpa

GAIN_MAX = 1e4            # N*m, N*m*s/rad: far above any attitude gain; keeps every product finite
TORQUE_MAX_MAX = 100.0    # N*m
INERTIA_MAX = 1e6         # kg*m^2 per entry
PATH_MAX = 255


class GpParamsError(CodegenError):
    """A bad GP-law parameter (file): missing/unknown key, bad value, unreadable file or artifact."""


_SCALAR_KEYS = ("k1", "k1_bar", "k2", "k2_bar", "torque_max")
_KEYS = ("artifact",) + _SCALAR_KEYS + ("inertia",)


@dataclass(frozen=True)
class GpLawParams:
    """The law's constants (SI units) and the trained GP they fly with."""

    gp: gpa.GpArtifact
    k1: float = 4.0
    k1_bar: float = 16.0
    k2: float = 72.0
    k2_bar: float = 144.0
    torque_max: float = 1.0
    inertia: tuple[tuple[float, float, float], ...] = ((1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (0.0, 0.0, 1.0))
    artifact_name: str = "artifact.json"     # as written in the file (documentation only)

    def __post_init__(self):
        validate(self)

    @property
    def n_inducing(self) -> int:
        return self.gp.arrays.n_inducing

    def law_mapping(self) -> dict:
        """The law's constants as the file writes them (without the artifact)."""
        return {"k1": float(self.k1), "k1_bar": float(self.k1_bar), "k2": float(self.k2), "k2_bar": float(self.k2_bar),
                "torque_max": float(self.torque_max), "inertia": [[float(v) for v in r] for r in self.inertia]}

    def sha256(self) -> str:
        """sha256 of the law's constants and the artifact's seal (what the C bakes in)."""
        payload = {"law": self.law_mapping(), "artifact_sha256": self.gp.sha256}
        return hashlib.sha256(json.dumps(payload, sort_keys=True).encode("utf-8")).hexdigest()


def _fail(key: str, reason: str):
    raise GpParamsError(f"{key}: {reason}")


def validate(p: GpLawParams) -> None:
    if not isinstance(p.gp, gpa.GpArtifact):
        _fail("artifact", f"must be a GP artifact, got {type(p.gp).__name__}")
    for key in _SCALAR_KEYS:
        high = TORQUE_MAX_MAX if key == "torque_max" else GAIN_MAX
        values.float32_in(getattr(p, key), key, 0.0, high, low_open=True, error=GpParamsError)
    if not float(np.float32(p.k1)) <= float(np.float32(p.k1_bar)):
        _fail("k1_bar", f"must be >= k1 ({p.k1!r}), got {p.k1_bar!r}")
    if not float(np.float32(p.k2)) <= float(np.float32(p.k2_bar)):
        _fail("k2_bar", f"must be >= k2 ({p.k2!r}), got {p.k2_bar!r}")
    J = inertia_matrix(p.inertia)
    if not np.array_equal(J, J.T):
        _fail("inertia", "must be symmetric")
    if not np.linalg.eigvalsh(J)[0] > 0:
        _fail("inertia", "must be positive definite")


def _checked(value, key: str, low=None, high=None) -> float:
    """The file's float64 value once its float32 rounding passes the range check (the C rounds it)."""
    values.float32_in(value, key, low, high, error=GpParamsError)
    return float(value)


def inertia_matrix(inertia) -> np.ndarray:
    """The 3x3 inertia of a file's nested list, each entry checked (|J_ij| <= 1e6, normal float32 or 0)."""
    if not isinstance(inertia, (list, tuple)) or len(inertia) != 3:
        _fail("inertia", f"must be a 3x3 array, got {values.show(inertia)}")
    rows = []
    for i, row in enumerate(inertia):
        if not isinstance(row, (list, tuple)) or len(row) != 3:
            _fail(f"inertia[{i}]", f"must be a row of 3 numbers, got {values.show(row)}")
        rows.append([_checked(v, f"inertia[{i}][{j}]", -INERTIA_MAX, INERTIA_MAX) for j, v in enumerate(row)])
    return np.array(rows)


def _artifact_path(value, folder: Path) -> Path:
    """The artifact beside the law file or below its folder: a relative path without '..'."""
    if not isinstance(value, str) or not value:
        _fail("artifact", f"must be a file name (a string), got {values.show(value)}")
    if len(value) > PATH_MAX or not value.isprintable():
        _fail("artifact", f"must be a path of at most {PATH_MAX} printable characters, got {values.show(value)}")
    path = Path(value)
    if path.is_absolute() or ".." in path.parts:
        _fail("artifact", f"must be relative to the law file's folder, without '..', got {values.show(value)}")
    return folder / path


def load_params(path) -> GpLawParams:
    """Read and validate the law's .toml/.json file and the artifact it names; one-line errors."""
    path = Path(path)
    data = values.read_parameter_file(path, GpParamsError)
    if not isinstance(data, dict):
        raise GpParamsError(f"{path}: must hold a table of keys")
    unknown = sorted(set(data) - set(_KEYS))
    if unknown:
        raise GpParamsError(f"{path}: unknown key {values.show(unknown[0])} (known: {', '.join(_KEYS)})")
    missing = [k for k in _KEYS if k not in data]
    if missing:
        raise GpParamsError(f"{path}: missing key {missing[0]!r}")
    try:
        artifact_path = _artifact_path(data["artifact"], path.parent)
        try:
            gp = gpa.load(artifact_path)
        except ArtifactError as exc:
            raise GpParamsError(f"artifact: {exc}") from None
        scalars = {k: _checked(data[k], k) for k in _SCALAR_KEYS}
        inertia = tuple(tuple(r) for r in inertia_matrix(data["inertia"]).tolist())
        return GpLawParams(gp=gp, inertia=inertia, artifact_name=data["artifact"], **scalars)
    except GpParamsError as exc:
        raise GpParamsError(f"{path}: {exc}") from None
