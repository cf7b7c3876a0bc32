"""Parameter file schema of paper 000's tanh saturation law (eq. 10-20) and its one validator.

Lives in codegen because the C generator bakes the parameters in and codegen must not import
host; host.control.tanh_law re-exports every name. Errors are one-line `TanhParamsError`s (a
CodegenError, so the CLI prints them as one line).
"""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from codegen import values
from codegen.errors import CodegenError


class TanhParamsError(CodegenError):
    """A bad tanh-law parameter (file): missing/unknown key, bad value, unreadable file."""


# file key -> dataclass field; "lambda" is a Python keyword.
_GAIN_KEYS = ("k1", "k2", "k3", "k4", "k5", "eps1", "eps2", "eps3", "beta1", "beta2")
_POSITIVE_KEYS = _GAIN_KEYS + ("eta", "n1", "lambda", "d_max")
_REQUIRED_KEYS = _POSITIVE_KEYS + ("gamma", "inertia")
_OPTIONAL_KEYS = ("delta_reg", "q0_min", "varpi_limit")
_FIELD_OF_KEY = {"lambda": "lam"}


@dataclass(frozen=True)
class TanhParams:
    """Parameters of law (17)-(20) with virtual rate (10)-(11); units SI (N·m, rad, rad/s, kg·m²).

    k1, k2, k3   tanh amplitudes of (17) (N·m): |u_i| ≤ k1 + k2 + k3.
    eps1..eps3   tanh slopes of (17) on ϖ, x1 and ẋ1 (not the ε1 of the adaptive law (16)).
    k4, k5       δ feedback gain and constant term of the auxiliary system (18).
    beta1, beta2 linear and power-law gains of the virtual rate (10).
    gamma        exponent of f (11) and of sig(δ)^γ in (20), in (0, 1).
    eta          switch of f (11) between its quadratic patch and sig(x)^γ.
    n1           switch of u_a (20) between δ/‖δ‖ and sig(δ)^γ/n1^γ.
    lam          log-barrier gain λ of (10).
    d_max        disturbance bound (N·m) of (18) and (20); not printed in the paper.
    inertia      J (kg·m²), symmetric positive definite, used by F (7) and J⁻¹ in (18), (20).
    delta_reg    δᵀδ threshold *and* offset of the section 4.2 regularisation of δ/(δᵀδ).
    q0_min       scalar part of the error quaternion below which the 180° fallback runs.
    varpi_limit  |ϖ_i| clamp of the sampled update (overflow guard for too-long periods; never
                 reached in the paper's example at T ≤ 0.19 s, where max |ϖ_i| < 10).
    """

    k1: float
    k2: float
    k3: float
    k4: float
    k5: float
    eps1: float
    eps2: float
    eps3: float
    beta1: float
    beta2: float
    gamma: float
    eta: float
    n1: float
    lam: float
    d_max: float
    inertia: tuple[tuple[float, float, float], ...]
    delta_reg: float = 1e-3
    q0_min: float = 0.01
    varpi_limit: float = 1e6

    def __post_init__(self):
        _validate(self)
        # normalise to floats so equality, hashing and the generated constants do not depend on
        # whether a file wrote 7 or 7.0
        for key in _REQUIRED_KEYS + _OPTIONAL_KEYS:
            name = _FIELD_OF_KEY.get(key, key)
            value = getattr(self, name)
            if name == "inertia":
                value = tuple(tuple(float(x) for x in row) for row in value)
            else:
                value = float(value)
            object.__setattr__(self, name, value)

    def to_mapping(self) -> dict:
        """The file form (keys as in a parameter file), for JSON/TOML and the C generator."""
        out = {key: getattr(self, _FIELD_OF_KEY.get(key, key)) for key in _REQUIRED_KEYS + _OPTIONAL_KEYS}
        out["inertia"] = [list(row) for row in self.inertia]
        return out


def _validate(p: TanhParams) -> None:
    for key in _REQUIRED_KEYS + _OPTIONAL_KEYS:
        if key == "inertia":
            continue
        value = getattr(p, _FIELD_OF_KEY.get(key, key))
        if not values.is_number(value):
            raise TanhParamsError(f"'{key}' must be a finite number, got {values.show(value)}")
        values.real(value, f"'{key}'", TanhParamsError)     # finite, within float32 (also a 400-digit integer)
    for key in _POSITIVE_KEYS + _OPTIONAL_KEYS:
        value = getattr(p, _FIELD_OF_KEY.get(key, key))
        if value <= 0:
            raise TanhParamsError(f"'{key}' = {value!r} must be > 0")
    if not 0.0 < p.gamma < 1.0:
        raise TanhParamsError(f"'gamma' = {p.gamma!r} must be in (0, 1)")
    if not p.q0_min < 0.5:
        raise TanhParamsError(f"'q0_min' = {p.q0_min!r} must be < 0.5 (it guards only the 180° neighbourhood)")
    _validate_float32(p)
    _validate_inertia(p.inertia)


def _validate_float32(p: TanhParams) -> None:
    """The ranges again on the float32 the C holds (1e-50 would become 0, 0.99999999 would become 1)."""
    for key in _POSITIVE_KEYS + _OPTIONAL_KEYS:
        values.float32_in(getattr(p, _FIELD_OF_KEY.get(key, key)), f"'{key}'", 0.0, low_open=True,
                          error=TanhParamsError)
    values.float32_in(p.gamma, "'gamma'", 0.0, 1.0, low_open=True, high_open=True, error=TanhParamsError)


def _validate_inertia(inertia) -> None:
    if isinstance(inertia, np.ndarray):
        inertia = inertia.tolist()
    if (not isinstance(inertia, (list, tuple)) or len(inertia) != 3
            or not all(isinstance(row, (list, tuple)) and len(row) == 3 for row in inertia)):
        raise TanhParamsError(f"'inertia' must be a finite 3x3 matrix, got {values.show(inertia)}")
    for i, row in enumerate(inertia):
        for j, x in enumerate(row):   # numbers only: no "2_4.6" strings or booleans through float()
            values.float32_in(x, f"'inertia'[{i}][{j}]", error=TanhParamsError)
    J = np.array(inertia, dtype=float)
    if not np.allclose(J, J.T, rtol=0, atol=1e-12 * np.max(np.abs(J))):
        raise TanhParamsError("'inertia' must be symmetric")
    if np.min(np.linalg.eigvalsh(J)) <= 0:
        raise TanhParamsError("'inertia' must be positive definite")


def params_from_mapping(data: dict) -> TanhParams:
    """Build validated parameters from a parameter-file mapping; errors are one-line TanhParamsErrors."""
    if not isinstance(data, dict):
        raise TanhParamsError(f"parameters must be a table/object, got {type(data).__name__}")
    unknown = sorted(set(data) - set(_REQUIRED_KEYS) - set(_OPTIONAL_KEYS))
    if unknown:
        raise TanhParamsError(f"unknown key '{unknown[0]}'")
    for key in _REQUIRED_KEYS:
        if key not in data:
            raise TanhParamsError(f"missing key '{key}'")
    kwargs = {_FIELD_OF_KEY.get(k, k): v for k, v in data.items()}
    inertia = kwargs["inertia"]
    if isinstance(inertia, (list, tuple)) and all(isinstance(r, (list, tuple)) for r in inertia):
        kwargs["inertia"] = tuple(tuple(r) for r in inertia)
    return TanhParams(**kwargs)


def load_params(path: str | Path) -> TanhParams:
    """Read a .toml or .json parameter file (flat keys, see TanhParams) and validate it."""
    path = Path(path)
    data = values.read_parameter_file(path, TanhParamsError)
    try:
        return params_from_mapping(data)
    except TanhParamsError as exc:
        raise TanhParamsError(f"{path}: {exc}") from None


def derived_constants(p: TanhParams) -> dict[str, object]:
    """float64 values the law needs beyond the parameters (host.control.tanh_law.compile_constants
    computes the same ones): J⁻¹, ‖J⁻¹‖ (spectral), r1, r2 of f (11), the u_a gains of (20)."""
    J = np.array(p.inertia, dtype=float)
    J_inv = np.linalg.inv(J)
    J_inv_norm = float(np.linalg.norm(J_inv, 2))
    g, eta = p.gamma, p.eta
    return {
        "J": J, "J_inv": J_inv, "J_inv_norm": J_inv_norm,
        "r1": (2.0 - g) * eta ** (g - 1.0),
        "r2": (g - 1.0) * eta ** (g - 2.0),
        "ua_gain": J_inv_norm * p.d_max,
        "ua_inner_scale": J_inv_norm * p.d_max / p.n1 ** g,
    }


def example_params() -> TanhParams:
    """A valid parameter set for the generic unit tests (not the paper's: docs/tanh_paper000.toml
    holds those), with other γ, gains and inertia so nothing is tuned to one set of numbers."""
    return params_from_mapping({
        "k1": 1.0, "k2": 1.2, "k3": 0.8, "k4": 3.0, "k5": 0.002, "eps1": 20.0, "eps2": 30.0, "eps3": 40.0,
        "beta1": 0.2, "beta2": 0.4, "gamma": 0.6, "eta": 0.002, "n1": 0.01, "lambda": 0.002, "d_max": 0.003,
        "inertia": [[3.0, 0.1, 0.0], [0.1, 2.0, -0.2], [0.0, -0.2, 4.0]]})
