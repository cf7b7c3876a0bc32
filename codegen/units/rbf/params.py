"""Parameter file schema of paper 002's RBF adaptive finite-time backstepping law and its one validator.

Lives in codegen because the C generator bakes the parameters in and codegen must not import
host; host.control.rbf_law re-exports what it needs. Errors are one-line `RbfParamsError`s (a
CodegenError, so the CLI prints them as one line). The law and every choice below:
docs/rbf-backstepping.md (sections 5-8 and 11).

Channel order everywhere: (rho, q_eps, q_beta, phi, theta, psi) for x1 and its gains; the RBF
input is e = [x1; x2] (12 values) scaled by 1/input_scale.
"""
from __future__ import annotations

from dataclasses import dataclass, fields
from pathlib import Path

import numpy as np

from codegen import values
from codegen.errors import CodegenError

NODES_MIN, NODES_MAX = 2, 15      # 15 nodes: 90 weights per network, well inside the 64 KB CCM
GAMMA_MAX = 1e4                  # adaptive gains gamma, gamma_delta
THETA_MAX_MAX = 1e6              # weight bounds theta_max[k]


class RbfParamsError(CodegenError):
    """A bad RBF-law parameter (file): missing/unknown key, bad value, unreadable file."""


_VECTOR_KEYS = {"k1": 6, "k2": 6, "input_scale": 12, "inertia": 3, "theta_max": 6}
_POSITIVE_KEYS = ("k3", "lambda", "delta", "gamma", "gamma_delta", "sigma", "mass", "force_max", "torque_max")
_REQUIRED_KEYS = ("theorem", "k1", "k2", "k3", "alpha", "lambda", "delta", "gamma", "gamma_delta", "nodes",
                  "centre_span", "sigma", "input_scale", "mass", "inertia", "force_max", "torque_max",
                  "theta_max")
# the box of valid inputs (docs/rbf-backstepping.md section 11): outside it the step refuses
_LIMIT_KEYS = ("rho_min", "rho_max", "tilt_max", "speed_max", "rate_max", "accel_max")
_OPTIONAL_KEYS = _LIMIT_KEYS
_FIELD_OF_KEY = {"lambda": "lam"}
# The smallest RBF input scale: every error in the valid box (|e_i| <= 2e6) divided by it, squared and
# summed over the 18 inputs stays finite in float32 (no inf - inf = NaN in the basis distance).
INPUT_SCALE_MIN = 1e-6
ANGLE_MAX = 3.5      # |angle| of every non-tilt angle input (rad): one 2*pi wrap brings a difference into [-pi, pi]


@dataclass(frozen=True)
class RbfParams:
    """Parameters of laws (17)-(18) (theorem 1) and (25)-(26) (theorem 2); SI units.

    theorem            1: one network (w); 2: adds the second network for G*Delta_u (saturation, dead zone).
    k1, k2             6 diagonal gains of nu (15) and of sig(z)^alpha (17), channel order above.
    k3                 variable-structure gain of sgn(z) (17).
    alpha              finite-time exponent, in (0, 1).
    lam                leakage of the adaptive laws (18), (26) (the paper's "small constant" lambda).
    delta              singularity guard Delta_i of the derivative gain eta (same for every channel).
    gamma, gamma_delta adaptive gains Gamma = gamma*I, Gamma_Delta = gamma_delta*I.
    nodes              Gaussian nodes N; centres c_j evenly spaced in [-centre_span, centre_span] in every
                       normalised coordinate; width sigma.
    input_scale        12 scales s_i: the RBF input is e_i / s_i.
    mass, inertia      nominal chaser mass (kg) and diagonal inertia (kg*m^2) the law uses.
    force_max          thrust limit per body axis (N); torque_max torque limit per body axis (N*m).
    theta_max          6 weight bounds, one per channel k: |theta_jk| <= theta_max[k] and the same for
                       theta_delta (units of that channel's x2-dot per unit basis value: m/s^2 for rho,
                       rad/s^2 for the others). gamma, gamma_delta <= GAMMA_MAX and each bound
                       <= THETA_MAX_MAX: with the generated
                       step's result guard nothing in a valid step can overflow (codegen/units/rbf/emit.py).
    rho_min..accel_max the box of valid inputs: rho and rho_d in [rho_min, rho_max] m; |q_eps|, |q_eps_d|,
                       |phi|, |phi_f| <= tilt_max rad; |range rates| <= speed_max m/s; |angular rates|
                       <= rate_max rad/s; |desired accelerations| <= accel_max (m/s^2, rad/s^2).
    """

    theorem: int
    k1: tuple[float, ...]
    k2: tuple[float, ...]
    k3: float
    alpha: float
    lam: float
    delta: float
    gamma: float
    gamma_delta: float
    nodes: int
    centre_span: float
    sigma: float
    input_scale: tuple[float, ...]
    mass: float
    inertia: tuple[float, float, float]
    force_max: float
    torque_max: float
    theta_max: tuple[float, ...]
    rho_min: float = 1.0
    rho_max: float = 10_000.0
    tilt_max: float = 1.2
    speed_max: float = 100.0
    rate_max: float = 1.0
    accel_max: float = 10.0

    def __post_init__(self):
        _validate(self)
        for f in fields(self):     # normalise so equality and the constants do not depend on 7 vs 7.0
            value = getattr(self, f.name)
            if f.name in ("theorem", "nodes"):
                continue
            value = tuple(float(x) for x in value) if isinstance(value, (tuple, list)) else float(value)
            object.__setattr__(self, f.name, value)

    def to_mapping(self) -> dict:
        """The file form (keys as in a parameter file)."""
        out = {}
        for key in _REQUIRED_KEYS + _OPTIONAL_KEYS:
            value = getattr(self, _FIELD_OF_KEY.get(key, key))
            out[key] = list(value) if isinstance(value, tuple) else value
        return out

    def centres(self) -> np.ndarray:
        """float64 node centres c_j (one scalar per node: the same value in every coordinate)."""
        return np.linspace(-self.centre_span, self.centre_span, self.nodes)


def _value(p: RbfParams, key: str):
    return getattr(p, _FIELD_OF_KEY.get(key, key))


def _validate(p: RbfParams) -> None:
    values.integer_in(p.theorem, "'theorem'", 1, 2, error=RbfParamsError)
    values.integer_in(p.nodes, "'nodes'", NODES_MIN, NODES_MAX, error=RbfParamsError)
    for key, n in _VECTOR_KEYS.items():
        v = _value(p, key)
        if not isinstance(v, (list, tuple)) or len(v) != n:
            raise RbfParamsError(f"'{key}': must be a list of {n} numbers, got {values.show(v)}")
        low = INPUT_SCALE_MIN if key == "input_scale" else 0.0
        for i, x in enumerate(v):
            values.float32_in(x, f"'{key}'[{i}]", low, low_open=low == 0.0, error=RbfParamsError)
    for key in _POSITIVE_KEYS + _LIMIT_KEYS:
        values.float32_in(_value(p, key), f"'{key}'", 0.0, low_open=True, error=RbfParamsError)
    values.float32_in(p.alpha, "'alpha'", 0.0, 1.0, low_open=True, high_open=True, error=RbfParamsError)
    values.float32_in(p.centre_span, "'centre_span'", 0.0, 10.0, error=RbfParamsError)
    values.float32_in(p.sigma, "'sigma'", 0.05, 100.0, error=RbfParamsError)
    values.float32_in(p.delta, "'delta'", 1e-6, 1.0, error=RbfParamsError)
    values.float32_in(p.tilt_max, "'tilt_max'", 0.0, 1.4, low_open=True, error=RbfParamsError)
    values.float32_in(p.rho_max, "'rho_max'", p.rho_min, 1e6, low_open=True, error=RbfParamsError)
    values.float32_in(p.speed_max, "'speed_max'", 0.0, 1e4, low_open=True, error=RbfParamsError)
    values.float32_in(p.rate_max, "'rate_max'", 0.0, 10.0, low_open=True, error=RbfParamsError)
    values.float32_in(p.accel_max, "'accel_max'", 0.0, 1e3, low_open=True, error=RbfParamsError)
    # caps that keep every intermediate of a valid step finite (codegen/units/rbf/emit.py, RESULT_MAX):
    # the adaptation's a = T gamma and the weight bounds
    for key in ("gamma", "gamma_delta"):
        values.float32_in(_value(p, key), f"'{key}'", 0.0, GAMMA_MAX, low_open=True, error=RbfParamsError)
    for i, x in enumerate(p.theta_max):
        values.float32_in(x, f"'theta_max'[{i}]", 0.0, THETA_MAX_MAX, low_open=True, error=RbfParamsError)
    # the leakage factor 1 - period*gamma*lambda stays in (0, 1] for any period <= 1 s
    if p.gamma * p.lam >= 1.0 or p.gamma_delta * p.lam >= 1.0:
        raise RbfParamsError(f"'gamma'*'lambda' and 'gamma_delta'*'lambda' must be < 1 (got {p.gamma * p.lam:g}, "
                             f"{p.gamma_delta * p.lam:g}): the leakage would flip the weights' sign")


def params_from_mapping(data: dict) -> RbfParams:
    """Validated parameters from a parameter-file mapping; errors are one-line RbfParamsErrors."""
    if not isinstance(data, dict):
        raise RbfParamsError(f"parameters must be a table/object, got {type(data).__name__}")
    unknown = sorted(set(data) - set(_REQUIRED_KEYS) - set(_OPTIONAL_KEYS))
    if unknown:
        raise RbfParamsError(f"unknown key {values.show(unknown[0])}")
    for key in _REQUIRED_KEYS:
        if key not in data:
            raise RbfParamsError(f"missing key '{key}'")
    kwargs = {_FIELD_OF_KEY.get(k, k): (tuple(v) if isinstance(v, list) else v) for k, v in data.items()}
    return RbfParams(**kwargs)


def load_params(path: str | Path) -> RbfParams:
    """Read a .toml or .json parameter file (flat keys, see RbfParams) and validate it."""
    path = Path(path)
    data = values.read_parameter_file(path, RbfParamsError)
    try:
        return params_from_mapping(data)
    except RbfParamsError as exc:
        raise RbfParamsError(f"{path}: {exc}") from None


# The paper's section 3.1 gains with this project's reconstructed choices (docs/rbf-backstepping.md
# section 8); docs/rbf_paper002.toml holds the same values as a file.
PAPER_MAPPING = {
    "theorem": 2,
    "k1": [0.28, 0.05, 0.10, 1.00, 1.00, 4.00], "k2": [6.50, 2.00, 2.60, 0.80, 0.36, 0.40],
    "k3": 1e-7, "alpha": 0.8, "lambda": 0.01, "delta": 0.01, "gamma": 1.0, "gamma_delta": 1.0,
    "nodes": 7, "centre_span": 1.5, "sigma": 1.0,
    "input_scale": [100.0, 0.2, 0.2, 0.2, 0.2, 0.2, 10.0, 0.05, 0.05, 0.1, 0.1, 0.1],
    "mass": 100.0, "inertia": [11.0, 13.2, 15.4], "force_max": 200.0, "torque_max": 0.5,
    "theta_max": [0.1, 0.001, 0.001, 0.01, 0.01, 0.01],
}


def paper_params(**overrides) -> RbfParams:
    return params_from_mapping({**PAPER_MAPPING, **overrides})


def example_params() -> RbfParams:
    """A valid parameter set for the generic unit tests (not the paper's), with other gains, node count,
    exponent and limits so nothing is tuned to one set of numbers."""
    return params_from_mapping({
        **PAPER_MAPPING, "k1": [0.3, 0.06, 0.12, 0.9, 1.1, 3.0], "k2": [5.0, 2.5, 2.0, 0.9, 0.5, 0.6],
        "k3": 1e-5, "alpha": 0.7, "lambda": 0.02, "delta": 0.02, "gamma": 2.0, "gamma_delta": 0.5,
        "nodes": 5, "centre_span": 1.2, "sigma": 0.8, "mass": 80.0, "inertia": [8.0, 9.0, 10.0],
        "force_max": 150.0, "torque_max": 0.4, "theta_max": [0.08, 0.002, 0.002, 0.02, 0.02, 0.02]})
