"""The GP artifact (`staregen.gp-artifact`, version 1; docs/gp-takeover.md §6-7).

A trained sparse GP (shared inducing points Z and SE-ARD kernel, one whitened variational
distribution (m̃_k, R_k) per output axis) as one sealed JSON file, in the envelope of the network
artifact (codegen/artifact.py, docs/artifact.md): `format`, `version`, `sha256` of the canonical
payload, hex-float strings, unknown fields refused (except in `metadata`), one-line errors
`file: json.path: reason`, the seal checked last.

The float64 fields (scales, hyperparameters, Z, m̃, R) are the model; the `flight` arrays (float32)
and the `conditioning` record are derived from them (`GpArrays.derive`) and re-derived on load:
the condition number must match to 1e-6 relative and be <= cond_max, every flight value must be
within 1 ulp of float32 of its re-derivation.

`reference_predict` is the float64 predictor from the arrays only (no gpytorch):
w = L⁻¹ k_Zx, μ_k = m̃_kᵀ w, σ²_k = k_xx + jitter − ‖w‖² + ‖R_kᵀ w‖² (GPyTorch's convention: its
VariationalStrategy adds the jitter to k_xx), then raw units (× s_y, × s_y²).
"""
from __future__ import annotations

import math
import os
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from scipy.linalg import solve_triangular

from codegen import artifact as art
from codegen import atomic
from codegen.artifact import ArtifactError, hex_float

FORMAT = "staregen.gp-artifact"
VERSION = 1
N_IN = 9
N_FLIGHT = 6
N_OUT = 3
MAX_INDUCING = 200
KERNEL = "rbf-ard"
INPUT_NAMES = ("q_v_x", "q_v_y", "q_v_z", "omega_x", "omega_y", "omega_z",
               "omega_dot_x", "omega_dot_y", "omega_dot_z")
INPUT_UNITS = ("1",) * 3 + ("rad/s",) * 3 + ("rad/s^2",) * 3
INPUT_SCALES = (0.2,) * 3 + (0.01,) * 3 + (5e-4,) * 3
COND_MAX = 1e6
COND_RTOL = 1e-6
MAGNITUDE_MAX = 1e30


# ----------------------------------------------------------------------------- the model arrays

def _packed(T: np.ndarray) -> np.ndarray:
    """Lower triangle of a square matrix, row by row."""
    return T[np.tril_indices(T.shape[-1])]


def _unpacked(p: np.ndarray, m: int) -> np.ndarray:
    T = np.zeros((m, m))
    T[np.tril_indices(m)] = p
    return T


def kernel_zz(Z: np.ndarray, lengthscale: np.ndarray, outputscale: float) -> np.ndarray:
    zt = Z / lengthscale
    d2 = ((zt[:, None, :] - zt[None, :, :]) ** 2).sum(-1)
    return outputscale * np.exp(-0.5 * d2)


@dataclass(frozen=True)
class Conditioning:
    cond: float
    cond_max: float
    min_eig: float
    s_max: tuple[float, ...]


@dataclass(frozen=True)
class GpArrays:
    """The float64 model (normalised units inside): everything the flight arrays derive from."""

    input_scale: np.ndarray      # (9,)
    output_scale: np.ndarray     # (3,) s_y, N·m
    lengthscale: np.ndarray      # (9,)
    outputscale: float           # σ_f²
    noise: np.ndarray            # (3,) normalised units
    jitter: float
    Z: np.ndarray                # (M, 9)
    m: np.ndarray                # (3, M) whitened
    R: np.ndarray                # (3, M, M) lower

    @property
    def n_inducing(self) -> int:
        return int(self.Z.shape[0])

    def chol(self) -> np.ndarray:
        """L = chol(K_ZZ + jitter I), float64; a CodegenError-friendly LinAlgError if not positive definite."""
        K = kernel_zz(self.Z, self.lengthscale, self.outputscale) + self.jitter * np.eye(self.n_inducing)
        return np.linalg.cholesky(K)

    def linv(self) -> np.ndarray:
        L = self.chol()
        return _solve_lower(L, np.eye(self.n_inducing))

    def conditioning(self, cond_max: float = COND_MAX) -> Conditioning:
        K = kernel_zz(self.Z, self.lengthscale, self.outputscale) + self.jitter * np.eye(self.n_inducing)
        eig = np.linalg.eigvalsh(K)
        s_max = tuple(float(np.linalg.eigvalsh(Rk @ Rk.T)[-1]) for Rk in self.R)
        return Conditioning(cond=float(eig[-1] / eig[0]), cond_max=float(cond_max), min_eig=float(eig[0]),
                            s_max=s_max)

    def flight(self) -> dict[str, np.ndarray]:
        """The float32 arrays of §6-7 (ω̇ coordinates folded at ω̇ = 0)."""
        ell = self.lengthscale
        zt = self.Z / ell
        f32 = lambda a: np.asarray(a, dtype=np.float64).astype(np.float32)  # noqa: E731
        return {
            "g": f32(1.0 / (self.input_scale[:N_FLIGHT] * ell[:N_FLIGHT])),
            "zt": f32(zt[:, :N_FLIGHT]),
            "c": f32(-0.5 * (zt[:, N_FLIGHT:] ** 2).sum(1)),
            "A": f32(_packed(self.outputscale * self.linv())),
            "m": f32(self.m),
            "R": f32(np.stack([_packed(Rk) for Rk in self.R])),
            "kxx": f32(self.outputscale),
            "inv_kxx": f32(1.0 / self.outputscale),
            "mu_scale": f32(self.output_scale),
            "var_scale": f32(self.output_scale ** 2),
        }


def _solve_lower(L: np.ndarray, B: np.ndarray) -> np.ndarray:
    return solve_triangular(L, B, lower=True)


def reference_predict(a: GpArrays, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Float64 latent mean and variance (N×3 each, raw units: N·m, (N·m)²) at raw inputs x (N×9)."""
    x = np.atleast_2d(np.asarray(x, dtype=np.float64))
    xt = x / a.input_scale / a.lengthscale
    zt = a.Z / a.lengthscale
    d2 = ((xt[:, None, :] - zt[None, :, :]) ** 2).sum(-1)          # N×M
    k = a.outputscale * np.exp(-0.5 * d2)
    W = _solve_lower(a.chol(), k.T)                                # M×N = L⁻¹ k_Zx
    mean = (a.m @ W).T                                             # N×3
    nys = a.outputscale + a.jitter - (W ** 2).sum(0)               # N
    var = np.stack([nys + ((Rk.T @ W) ** 2).sum(0) for Rk in a.R], axis=1)
    return mean * a.output_scale, var * a.output_scale ** 2


def flight_predict(fl: dict[str, np.ndarray], q_v: np.ndarray, omega: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The §6/§11 flight formula evaluated in float64 on the float32 arrays (ω̇ = 0, no clamps):
    a cross-check of the folding, not the golden model."""
    q_v = np.atleast_2d(q_v)
    omega = np.atleast_2d(omega)
    xt = np.concatenate([q_v, omega], axis=1) * fl["g"].astype(np.float64)
    zt = fl["zt"].astype(np.float64)
    t = fl["c"].astype(np.float64)[None, :] - 0.5 * ((xt[:, None, :] - zt[None, :, :]) ** 2).sum(-1)
    khat = np.exp(t)
    M = zt.shape[0]
    A = _unpacked(fl["A"].astype(np.float64), M)
    W = A @ khat.T
    r = float(fl["kxx"]) - (W ** 2).sum(0)
    mean = (fl["m"].astype(np.float64) @ W).T
    var = np.stack([r + ((_unpacked(Rp.astype(np.float64), M).T @ W) ** 2).sum(0) for Rp in fl["R"]], axis=1)
    return mean * fl["mu_scale"].astype(np.float64), var * fl["var_scale"].astype(np.float64)


# ----------------------------------------------------------------------------- the artifact

@dataclass(frozen=True)
class GpArtifact:
    arrays: GpArrays
    envelope_min: np.ndarray     # (9,) raw training-input range
    envelope_max: np.ndarray
    cond_max: float = COND_MAX
    metadata: dict = field(default_factory=dict)
    # A loaded artifact keeps the file's float32 flight arrays and conditioning record (checked against
    # their re-derivation on load): the C and the seal then depend on the file only, not on the LAPACK
    # of the machine that builds (a re-derivation may differ by 1 float32 ulp).
    recorded_flight: dict | None = field(default=None, repr=False, compare=False)
    recorded_conditioning: Conditioning | None = field(default=None, repr=False, compare=False)

    def __post_init__(self):
        validate(self)

    @property
    def conditioning(self) -> Conditioning:
        return self.arrays.conditioning(self.cond_max)

    @property
    def flight(self) -> dict[str, np.ndarray]:
        """The float32 arrays the flight C bakes in: the file's when loaded, else derived."""
        return dict(self.recorded_flight) if self.recorded_flight is not None else self.arrays.flight()

    def payload(self) -> dict:
        return _payload_of(self)

    @property
    def sha256(self) -> str:
        return art.payload_sha256(self.payload())

    def document(self) -> dict:
        return art.sealed(FORMAT, VERSION, self.payload())

    def to_json(self) -> str:
        return art.pretty_json(self.document()) + "\n"

    def save(self, path: str | os.PathLike) -> Path:
        path = Path(path)
        atomic.write_text(path, self.to_json())
        return path


def _h64(values) -> list:
    return [hex_float(float(v)) for v in np.asarray(values, dtype=np.float64).reshape(-1)]


def _h32(values) -> list:
    return [hex_float(float(v)) for v in np.asarray(values, dtype=np.float32).reshape(-1)]


def _payload_of(g: GpArtifact) -> dict:
    a = g.arrays
    M = a.n_inducing
    c = g.recorded_conditioning or g.conditioning
    fl = g.flight
    return {
        "model": {"n_inducing": M, "n_out": N_OUT, "kernel": KERNEL,
                  "train_inputs": {"names": list(INPUT_NAMES), "units": list(INPUT_UNITS)},
                  "flight_inputs": N_FLIGHT,
                  "fixed_inputs": {"names": list(INPUT_NAMES[N_FLIGHT:]), "value": hex_float(0.0)}},
        "scales": {"input": _h64(a.input_scale), "output": _h64(a.output_scale)},
        "hyper": {"lengthscale": _h64(a.lengthscale), "outputscale": hex_float(a.outputscale),
                  "noise": _h64(a.noise), "jitter": hex_float(a.jitter)},
        "inducing": {"Z": [_h64(row) for row in a.Z]},
        "variational": {"m": [_h64(row) for row in a.m], "R": [_h64(_packed(Rk)) for Rk in a.R]},
        "flight": {
            "g": _h32(fl["g"]), "zt": [_h32(row) for row in fl["zt"]], "c": _h32(fl["c"]), "A": _h32(fl["A"]),
            "m": [_h32(row) for row in fl["m"]], "R": [_h32(row) for row in fl["R"]],
            "kxx": hex_float(float(fl["kxx"])), "inv_kxx": hex_float(float(fl["inv_kxx"])),
            "mu_scale": _h32(fl["mu_scale"]), "var_scale": _h32(fl["var_scale"]),
        },
        "conditioning": {"cond": hex_float(c.cond), "cond_max": hex_float(c.cond_max),
                         "min_eig": hex_float(c.min_eig), "s_max": _h64(c.s_max)},
        "envelope": {"min": _h64(g.envelope_min), "max": _h64(g.envelope_max)},
        "metadata": dict(g.metadata),
    }


def _fail(path: str, reason: str):
    raise ArtifactError(path, reason)


def _finite(arr, path: str) -> None:
    arr = np.asarray(arr, dtype=np.float64)
    bad = ~np.isfinite(arr)
    if bad.any():
        idx = np.argwhere(bad)[0]
        _fail(f"{path}{''.join(f'[{i}]' for i in idx)}", f"must be finite, got {arr[tuple(idx)]!r}")


def validate(g: GpArtifact) -> None:
    """Everything `load` checks except the seal and the recorded-vs-recomputed comparisons."""
    a = g.arrays
    M = a.n_inducing
    if not 1 <= M <= MAX_INDUCING:
        _fail("payload.model.n_inducing", f"must be in [1, {MAX_INDUCING}], got {M}")
    shapes = {"payload.scales.input": (a.input_scale, (N_IN,)), "payload.scales.output": (a.output_scale, (N_OUT,)),
              "payload.hyper.lengthscale": (a.lengthscale, (N_IN,)), "payload.hyper.noise": (a.noise, (N_OUT,)),
              "payload.inducing.Z": (a.Z, (M, N_IN)), "payload.variational.m": (a.m, (N_OUT, M)),
              "payload.variational.R": (a.R, (N_OUT, M, M)),
              "payload.envelope.min": (g.envelope_min, (N_IN,)), "payload.envelope.max": (g.envelope_max, (N_IN,))}
    for path, (arr, shape) in shapes.items():
        if np.shape(arr) != shape:
            _fail(path, f"shape mismatch: expected {shape}, got {np.shape(arr)}")
        _finite(arr, path)
    for path, v in (("payload.hyper.outputscale", a.outputscale), ("payload.hyper.jitter", a.jitter),
                    ("payload.conditioning.cond_max", g.cond_max)):
        _finite(v, path)
    for path, arr in (("payload.scales.input", a.input_scale), ("payload.scales.output", a.output_scale),
                      ("payload.hyper.lengthscale", a.lengthscale), ("payload.hyper.noise", a.noise)):
        if not (np.asarray(arr) > 0).all():
            _fail(path, "every value must be > 0")
    if not a.outputscale > 0:
        _fail("payload.hyper.outputscale", f"must be > 0, got {a.outputscale!r}")
    if not 0 <= a.jitter <= 1e-2:
        _fail("payload.hyper.jitter", f"must be in [0, 0.01], got {a.jitter!r}")
    if not g.cond_max >= 1:
        _fail("payload.conditioning.cond_max", f"must be >= 1, got {g.cond_max!r}")
    if not (np.asarray(g.envelope_min) <= np.asarray(g.envelope_max)).all():
        _fail("payload.envelope", "min must be <= max")
    for k, Rk in enumerate(a.R):
        if not (np.diag(Rk) > 0).all():
            _fail(f"payload.variational.R[{k}]", "diagonal entries must be > 0")
        if np.triu(Rk, 1).any():
            _fail(f"payload.variational.R[{k}]", "must be lower triangular")
    try:
        a.chol()
    except np.linalg.LinAlgError:
        _fail("payload.inducing.Z", "K_ZZ + jitter I is not positive definite (duplicate inducing points?)")
    c = a.conditioning(g.cond_max)
    if not c.cond <= g.cond_max:
        _fail("payload.conditioning.cond", f"condition number {c.cond:.6g} of K_ZZ + jitter I exceeds "
                                            f"cond_max {g.cond_max:g} (a training failure: refuse, do not re-jitter)")
    fl = a.flight()
    for name in ("g", "zt", "c", "A", "m", "R", "mu_scale", "var_scale"):
        with np.errstate(over="ignore"):
            _finite(fl[name], f"payload.flight.{name}")
    bound = np.abs(fl["A"].astype(np.float64)).sum() * np.abs(fl["m"].astype(np.float64)).sum() \
        * float(np.max(fl["mu_scale"]))
    if not bound < MAGNITUDE_MAX:
        _fail("payload.flight", f"magnitude bound sum|A'| sum|m| max s_y = {bound:.3g} is not below {MAGNITUDE_MAX:g}")
    if not np.isfinite(fl["inv_kxx"]) or not np.isfinite(fl["kxx"]) or fl["kxx"] <= 0:
        _fail("payload.flight.kxx", "outputscale does not round to a positive finite float32")


# ----------------------------------------------------------------------------- loader

_R = art.DocumentReader


def _real_list(r, value, path: str, n: int, float32: bool) -> np.ndarray:
    items = r.list(value, path, n)
    return np.array([r.real(v, f"{path}[{i}]", float32) for i, v in enumerate(items)], dtype=np.float64)


def _real_matrix(r, value, path: str, rows: int, cols: int, float32: bool) -> np.ndarray:
    items = r.list(value, path, rows)
    return np.stack([_real_list(r, row, f"{path}[{i}]", cols, float32) for i, row in enumerate(items)]) \
        if rows else np.zeros((0, cols))


def _ulp_close(recorded: np.ndarray, derived: np.ndarray) -> bool:
    """Within 1 ulp of float32 (LAPACK may differ in the last float64 bit between machines)."""
    a = np.asarray(recorded, dtype=np.float32).reshape(-1)
    b = np.asarray(derived, dtype=np.float32).reshape(-1)
    return bool((np.abs(a.astype(np.float64) - b.astype(np.float64))
                 <= np.spacing(np.maximum(np.abs(a), np.abs(b))).astype(np.float64)).all())


def from_document(doc: Any, source: str | None = None) -> GpArtifact:
    """Validate a parsed JSON document and build the GpArtifact; the sha256 seal is checked last."""
    r = _R(source)
    p = art.read_envelope(r, doc, FORMAT, VERSION, ("model", "scales", "hyper", "inducing", "variational", "flight",
                                                    "conditioning", "envelope", "metadata"))
    model = r.obj(p["model"], "payload.model", ("n_inducing", "n_out", "kernel", "train_inputs", "flight_inputs",
                                                "fixed_inputs"))
    M = model["n_inducing"]
    if isinstance(M, bool) or not isinstance(M, int) or not 1 <= M <= MAX_INDUCING:
        r.fail("payload.model.n_inducing", f"expected an integer in [1, {MAX_INDUCING}], got {str(M)[:20]}")
    if model["n_out"] != N_OUT or isinstance(model["n_out"], bool):
        r.fail("payload.model.n_out", f"expected {N_OUT}, got {str(model['n_out'])[:20]}")
    if model["kernel"] != KERNEL:
        r.fail("payload.model.kernel", f"expected {KERNEL!r}, got {str(model['kernel'])[:40]!r}")
    if model["flight_inputs"] != N_FLIGHT or isinstance(model["flight_inputs"], bool):
        r.fail("payload.model.flight_inputs", f"expected {N_FLIGHT}, got {str(model['flight_inputs'])[:20]}")
    ti = r.obj(model["train_inputs"], "payload.model.train_inputs", ("names", "units"))
    if r.strings(ti["names"], "payload.model.train_inputs.names", N_IN) != INPUT_NAMES:
        r.fail("payload.model.train_inputs.names", f"expected {list(INPUT_NAMES)}")
    if r.strings(ti["units"], "payload.model.train_inputs.units", N_IN) != INPUT_UNITS:
        r.fail("payload.model.train_inputs.units", f"expected {list(INPUT_UNITS)}")
    fi = r.obj(model["fixed_inputs"], "payload.model.fixed_inputs", ("names", "value"))
    if r.strings(fi["names"], "payload.model.fixed_inputs.names", N_IN - N_FLIGHT) != INPUT_NAMES[N_FLIGHT:]:
        r.fail("payload.model.fixed_inputs.names", f"expected {list(INPUT_NAMES[N_FLIGHT:])}")
    if r.real(fi["value"], "payload.model.fixed_inputs.value", False) != 0.0:
        r.fail("payload.model.fixed_inputs.value", "expected 0 (flight evaluates at omega_dot = 0)")
    sc = r.obj(p["scales"], "payload.scales", ("input", "output"))
    hy = r.obj(p["hyper"], "payload.hyper", ("lengthscale", "outputscale", "noise", "jitter"))
    ind = r.obj(p["inducing"], "payload.inducing", ("Z",))
    va = r.obj(p["variational"], "payload.variational", ("m", "R"))
    fl = r.obj(p["flight"], "payload.flight", ("g", "zt", "c", "A", "m", "R", "kxx", "inv_kxx", "mu_scale",
                                               "var_scale"))
    co = r.obj(p["conditioning"], "payload.conditioning", ("cond", "cond_max", "min_eig", "s_max"))
    en = r.obj(p["envelope"], "payload.envelope", ("min", "max"))
    metadata = r.obj(p["metadata"], "payload.metadata", (), open_ended=True)
    P = M * (M + 1) // 2
    R_packed = _real_matrix(r, va["R"], "payload.variational.R", N_OUT, P, False)
    arrays = GpArrays(
        input_scale=_real_list(r, sc["input"], "payload.scales.input", N_IN, False),
        output_scale=_real_list(r, sc["output"], "payload.scales.output", N_OUT, False),
        lengthscale=_real_list(r, hy["lengthscale"], "payload.hyper.lengthscale", N_IN, False),
        outputscale=r.real(hy["outputscale"], "payload.hyper.outputscale", False),
        noise=_real_list(r, hy["noise"], "payload.hyper.noise", N_OUT, False),
        jitter=r.real(hy["jitter"], "payload.hyper.jitter", False),
        Z=_real_matrix(r, ind["Z"], "payload.inducing.Z", M, N_IN, False),
        m=_real_matrix(r, va["m"], "payload.variational.m", N_OUT, M, False),
        R=np.stack([_unpacked(row, M) for row in R_packed]),
    )
    recorded = {
        "g": _real_list(r, fl["g"], "payload.flight.g", N_FLIGHT, True),
        "zt": _real_matrix(r, fl["zt"], "payload.flight.zt", M, N_FLIGHT, True),
        "c": _real_list(r, fl["c"], "payload.flight.c", M, True),
        "A": _real_list(r, fl["A"], "payload.flight.A", P, True),
        "m": _real_matrix(r, fl["m"], "payload.flight.m", N_OUT, M, True),
        "R": _real_matrix(r, fl["R"], "payload.flight.R", N_OUT, P, True),
        "kxx": np.array(r.real(fl["kxx"], "payload.flight.kxx", True)),
        "inv_kxx": np.array(r.real(fl["inv_kxx"], "payload.flight.inv_kxx", True)),
        "mu_scale": _real_list(r, fl["mu_scale"], "payload.flight.mu_scale", N_OUT, True),
        "var_scale": _real_list(r, fl["var_scale"], "payload.flight.var_scale", N_OUT, True),
    }
    cond = r.real(co["cond"], "payload.conditioning.cond", False)
    cond_max = r.real(co["cond_max"], "payload.conditioning.cond_max", False)
    min_eig = r.real(co["min_eig"], "payload.conditioning.min_eig", False)
    s_max = _real_list(r, co["s_max"], "payload.conditioning.s_max", N_OUT, False)
    try:
        g = GpArtifact(arrays=arrays,
                       envelope_min=_real_list(r, en["min"], "payload.envelope.min", N_IN, False),
                       envelope_max=_real_list(r, en["max"], "payload.envelope.max", N_IN, False),
                       cond_max=cond_max, metadata=dict(metadata))
    except ArtifactError as exc:
        raise ArtifactError(exc.field_path, exc.reason, source) from None
    actual = g.conditioning
    if not abs(actual.cond - cond) <= COND_RTOL * actual.cond:
        r.fail("payload.conditioning.cond", f"recorded {cond:.9g}, recomputed {actual.cond:.9g} from Z, "
                                             "lengthscale, outputscale and jitter")
    derived = g.flight
    for name, value in recorded.items():
        if not _ulp_close(value, derived[name]):
            r.fail(f"payload.flight.{name}", "differs by more than 1 float32 ulp from its re-derivation from "
                                             "the float64 fields")
    art.check_seal(r, doc)
    kept = {name: np.asarray(value, dtype=np.float32) for name, value in recorded.items()}
    record = Conditioning(cond=cond, cond_max=cond_max, min_eig=min_eig, s_max=tuple(float(v) for v in s_max))
    return GpArtifact(arrays=arrays, envelope_min=g.envelope_min, envelope_max=g.envelope_max, cond_max=cond_max,
                      metadata=g.metadata, recorded_flight=kept, recorded_conditioning=record)


def load(path: str | os.PathLike) -> GpArtifact:
    """Read and validate a GP artifact file; any problem is one line `file: json.path: reason`."""
    return from_document(art.read_document(path), str(path))


def parse(text: str, source: str | None = None) -> GpArtifact:
    return from_document(art.parse_json(text, source), source)
