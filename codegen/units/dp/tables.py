"""The discrete-point tables artifact: the anchor samples (float32 inputs in Table 2 units and their
optimal torques) and the settings, one sealed JSON file the flight C is generated from.

File (docs/discrete-point.md states it field by field):
    {"format": "staregen.dp-tables", "version": 1, "sha256": <of the payload>,
     "payload": {"params": {r, s_limit, n_min, iterations, tukey_c, ridge, widen},
                 "samples": {"n": N, "x": base64 of N x 12 little-endian float32 (row-major),
                             "y": base64 of N x 3 little-endian float32},
                 "metadata": {"creator": str, "dataset_sha256": hex64 | null, "seed": int | null}}}

Derived here, for the C and the golden model alike (`DpTables`): the per-dimension sample IDs in
ascending value order (a stable argsort, paper 003's X3; X2 is not stored, the bisection reads
X[X3]), the box half-widths of every level and 1/range, all rounded to float32 once.

Flash on the STM32F417: 84 bytes per sample (x 48, y 12, X3 12 x uint16); the tables may use the
1 MiB flash less 128 KiB kept for code (`TABLE_FLASH_BUDGET`), so at most 10,922 samples.
"""
from __future__ import annotations

import base64
import binascii
import json
import os
import re
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from codegen import atomic
from codegen.artifact import (TABLE2_MAX, TABLE2_MIN, ArtifactError, comment_text_problem, payload_sha256,
                               read_document, seal_problem, sealed)
from codegen.units.dp.params import N_IN, N_OUT, DpParams, DpParamsError

FORMAT = "staregen.dp-tables"
VERSION = 1
FLASH_BYTES = 1 << 20                 # STM32F417VG/IG: 1 MiB
CODE_RESERVE = 128 << 10              # kept for the step's code, the other units and the firmware
TABLE_FLASH_BUDGET = FLASH_BYTES - CODE_RESERVE
BYTES_PER_SAMPLE = 4 * N_IN + 4 * N_OUT + 2 * N_IN
MAX_SAMPLES = min(TABLE_FLASH_BUDGET // BYTES_PER_SAMPLE, 0xFFFF)   # uint16 IDs
STACK_BUDGET = 16 << 10               # the step's scratch lives on the stack (SPEC 5: no global mutable state)
MEAN_ABS_TO_SIGMA = 1.2533141373155003   # sqrt(pi/2): E|e| = sigma·sqrt(2/pi) for Gaussian residuals


def stack_estimate(s_limit: int) -> int:
    """The step's stack: per selected point its ID (uint16) and one residual / weight (float32); the
    13 x 13 system, its factor and the box (about 3.5 KiB; 4 KiB counted). The cycle report measures the real figure."""
    return s_limit * (2 + 4) + 4096


def flash_problem(n: int) -> str | None:
    need = n * BYTES_PER_SAMPLE
    if n > MAX_SAMPLES:
        return (f"{n:,} samples need {need:,} bytes of flash ({BYTES_PER_SAMPLE} per sample); the STM32F417's "
                f"budget for the tables is {TABLE_FLASH_BUDGET:,} bytes (1 MiB less {CODE_RESERVE >> 10} KiB for "
                f"code): at most {MAX_SAMPLES:,} samples")
    return None


@dataclass(frozen=True)
class DpTables:
    """Validated samples + settings, and the float32 constants derived from them."""
    X: np.ndarray                       # (N, 12) float32
    Y: np.ndarray                       # (N, 3) float32
    params: DpParams
    metadata: dict = field(default_factory=dict)

    def __post_init__(self):
        _check(self)
        X64 = self.X.astype(np.float64)
        span = X64.max(axis=0) - X64.min(axis=0)
        object.__setattr__(self, "order", np.argsort(self.X, axis=0, kind="stable").T.astype(np.uint16).copy())
        object.__setattr__(self, "span", span)
        with np.errstate(over="ignore"):
            half = np.array([0.5 * s * span for s in self.params.sides()]).astype(np.float32)
            inv = (1.0 / span).astype(np.float32)
        if not (np.all(np.isfinite(half)) and np.all(np.isfinite(inv)) and np.all(inv > 0)):
            raise ArtifactError("payload.samples.x", "input ranges too large or too small for float32 box widths")
        object.__setattr__(self, "half_widths", half)        # (L, 12) float32
        object.__setattr__(self, "inv_span", inv)            # (12,) float32

    @property
    def n(self) -> int:
        return int(self.X.shape[0])

    @property
    def n_levels(self) -> int:
        """Boxed levels; level n_levels is 'every sample'."""
        return int(self.half_widths.shape[0])

    @property
    def flash_bytes(self) -> int:
        return self.n * BYTES_PER_SAMPLE

    def payload(self) -> dict:
        return {"params": self.params.to_dict(),
                "samples": {"n": self.n, "x": _b64(self.X), "y": _b64(self.Y)},
                "metadata": dict(self.metadata)}

    @property
    def sha256(self) -> str:
        return payload_sha256(self.payload())

    def document(self) -> dict:
        return sealed(FORMAT, VERSION, self.payload())

    def save(self, path: str | os.PathLike) -> Path:
        return atomic.write_text(path, json.dumps(self.document(), indent=1) + "\n")


def _b64(a: np.ndarray) -> str:
    return base64.b64encode(np.ascontiguousarray(a, dtype="<f4").tobytes()).decode("ascii")


def _check(t: DpTables) -> None:
    if not isinstance(t.params, DpParams):
        raise ArtifactError("payload.params", "expected DpParams")
    try:
        t.params.validate()
    except DpParamsError as exc:
        raise ArtifactError("payload.params", str(exc)) from None
    for name, a, cols in (("x", t.X, N_IN), ("y", t.Y, N_OUT)):
        if not isinstance(a, np.ndarray) or a.dtype != np.float32 or a.ndim != 2 or a.shape[1] != cols:
            raise ArtifactError(f"payload.samples.{name}", f"expected an (N, {cols}) float32 array")
        if not np.all(np.isfinite(a)):
            raise ArtifactError(f"payload.samples.{name}", "every value must be finite")
    if t.X.shape[0] != t.Y.shape[0]:
        raise ArtifactError("payload.samples", f"x has {t.X.shape[0]} rows, y {t.Y.shape[0]}")
    n = t.X.shape[0]
    if n < t.params.n_min:
        raise ArtifactError("payload.samples.n", f"{n} samples, fewer than n_min = {t.params.n_min}")
    problem = flash_problem(n)
    if problem:
        raise ArtifactError("payload.samples.n", problem)
    need = stack_estimate(t.params.s_limit)
    if need > STACK_BUDGET:
        raise ArtifactError("payload.params.s_limit", f"S_limit = {t.params.s_limit} needs about {need:,} bytes of "
                            f"stack; the budget is {STACK_BUDGET:,}")
    constant = np.flatnonzero(t.X.max(axis=0) == t.X.min(axis=0))
    if constant.size:
        raise ArtifactError("payload.samples.x", f"input dimension {int(constant[0])} is constant (its range must be > 0)")
    _check_metadata(t.metadata)


def _check_metadata(meta) -> None:
    if not isinstance(meta, dict) or set(meta) - {"creator", "dataset_sha256", "seed"}:
        raise ArtifactError("payload.metadata", "expected an object with creator, dataset_sha256, seed only")
    creator = meta.get("creator", "")
    if not isinstance(creator, str) or comment_text_problem(creator):
        raise ArtifactError("payload.metadata.creator", comment_text_problem(creator) or "expected a string")
    sha = meta.get("dataset_sha256")
    if sha is not None and not (isinstance(sha, str) and re.fullmatch(r"[0-9a-f]{64}", sha)):
        raise ArtifactError("payload.metadata.dataset_sha256", "expected 64 lowercase hex digits or null")
    seed = meta.get("seed")
    if seed is not None and (isinstance(seed, bool) or not isinstance(seed, int) or not 0 <= seed < 2 ** 63):
        raise ArtifactError("payload.metadata.seed", "expected an integer in [0, 2^63) or null")


def from_arrays(X, Y, params: DpParams, metadata: dict | None = None) -> DpTables:
    X32 = np.ascontiguousarray(np.asarray(X, dtype=np.float64)).astype(np.float32)
    Y32 = np.ascontiguousarray(np.asarray(Y, dtype=np.float64)).astype(np.float32)
    return DpTables(X32, Y32, params, dict(metadata or {"creator": "staregen"}))


def random_tables(n: int = 300, params: DpParams | None = None, seed: int = 0) -> DpTables:
    """Samples in the Table 2 box with a smooth nonlinear torque (tests, the unit's example)."""
    rng = np.random.default_rng(seed)
    lo, hi = np.array(TABLE2_MIN), np.array(TABLE2_MAX)
    X = lo + (hi - lo) * rng.uniform(size=(n, N_IN))
    u = (X - lo) / (hi - lo) * 2 - 1
    Y = 0.05 * np.stack([np.sin(u[:, 0] + u[:, 6]) - u[:, 9], u[:, 1] * u[:, 7] - u[:, 10], np.tanh(u[:, 2] - u[:, 11])],
                        axis=1)
    return from_arrays(X, Y, params or DpParams(s_limit=32, n_min=20),
                       {"creator": "codegen.units.dp.tables.random_tables", "dataset_sha256": None, "seed": seed})


def _decode(value, path: str, n: int, cols: int) -> np.ndarray:
    if not isinstance(value, str):
        raise ArtifactError(path, "expected a base64 string")
    try:
        raw = base64.b64decode(value.encode("ascii"), validate=True)
    except (binascii.Error, UnicodeEncodeError):
        raise ArtifactError(path, "not valid base64") from None
    if len(raw) != n * cols * 4:
        raise ArtifactError(path, f"holds {len(raw)} bytes, expected {n} x {cols} float32 = {n * cols * 4}")
    return np.frombuffer(raw, dtype="<f4").reshape(n, cols).astype(np.float32)


def from_document(doc, source: str | None = None) -> DpTables:
    def fail(path, reason):
        raise ArtifactError(path, reason, source)
    if not isinstance(doc, dict) or set(doc) != {"format", "version", "sha256", "payload"}:
        fail("file", "expected an object with format, version, sha256, payload")
    if doc["format"] != FORMAT:
        fail("format", f"expected {FORMAT!r}, got {str(doc['format'])[:40]!r}")
    if doc["version"] != VERSION or isinstance(doc["version"], bool):
        fail("version", f"this staregen reads version {VERSION}, got {str(doc['version'])[:20]!r}")
    p = doc["payload"]
    if not isinstance(p, dict) or set(p) != {"params", "samples", "metadata"}:
        fail("payload", "expected an object with params, samples, metadata")
    problem = seal_problem(doc)
    if problem:
        fail("sha256", problem)
    if not isinstance(p["params"], dict) or set(p["params"]) != set(DpParams().to_dict()):
        fail("payload.params", f"expected exactly the keys {', '.join(sorted(DpParams().to_dict()))}")
    params = DpParams(**p["params"])
    try:
        params.validate()
    except DpParamsError as exc:
        fail("payload.params", str(exc))
    s = p["samples"]
    if not isinstance(s, dict) or set(s) != {"n", "x", "y"}:
        fail("payload.samples", "expected an object with n, x, y")
    n = s["n"]
    if isinstance(n, bool) or not isinstance(n, int) or n < 1:
        fail("payload.samples.n", "expected a positive integer")
    problem = flash_problem(n)
    if problem:
        fail("payload.samples.n", problem)
    try:
        X, Y = _decode(s["x"], "payload.samples.x", n, N_IN), _decode(s["y"], "payload.samples.y", n, N_OUT)
        return DpTables(X, Y, params, p["metadata"])
    except ArtifactError as exc:
        raise ArtifactError(exc.field_path, exc.reason, source) from None


def load(path: str | os.PathLike) -> DpTables:
    return from_document(read_document(path), str(path))
