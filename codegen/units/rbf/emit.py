"""C emitter of paper 002's RBF adaptive finite-time backstepping law (docs/rbf-backstepping.md
section 11): parameters + control period -> `<name>.h/.c`.

Every constant is computed in float64 from the parameters and rounded to float32 once, here, for
both the C (hex-float literals) and the golden twin (codegen/units/rbf/golden.py reads
`constants32`). Output is a pure function of (parameters, period, name, generator version):
byte-identical sources for the same inputs. The deterministic math library is copied next to the
law (codegen.cgen.math_sources); the powers |x|^(alpha - 1) come from the unit's own table
(codegen/units/tanh/powtab.py, the tanh law's K x^y with K = 1).
"""
from __future__ import annotations

import hashlib
import json
import math
import os
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from codegen import GENERATOR_VERSION, detmath
from codegen.cgen import c_float, check_name, unit_sources, write_sources
from codegen.errors import CodegenError
from codegen.units.rbf import records
from codegen.units.rbf.params import ANGLE_MAX, RbfParams
from codegen.units.tanh.powtab import PowTab, pow_tables
from codegen.values import float32_in

TEMPLATES = Path(__file__).with_name("templates")
DEFAULT_NAME = "rbf"
DEFAULT_PERIOD = 0.1  # s (docs/rbf-backstepping.md section 8)
MIN_PERIOD_S, MAX_PERIOD_S = 1e-4, 10.0
# The law's intermediate result guard: sum |v'_i| + sum |z_i| of a valid step must stay at or below
# this (else: STATUS_INVALID_INPUT, zero output, weights unchanged). With it, gamma <= GAMMA_MAX and
# theta_max <= THETA_MAX_MAX (params.py) nothing later in the step can overflow into a NaN.
RESULT_MAX = 1e30

# Step 1's box of |x| <= limit fields (rho and rho_d are checked against [rho_min, rho_max]):
# (field, component, limit); golden.in_box holds the same list.
BOX = tuple([("los", 1, "tilt_max"), ("los_d", 1, "tilt_max"), ("euler", 0, "tilt_max"), ("euler_d", 0, "tilt_max")]
            + [(f, j, "angle_max") for f, j in (("los", 2), ("euler", 1), ("euler", 2), ("los_d", 2),
                                                ("euler_d", 1), ("euler_d", 2))]
            + [("los_rate", 0, "speed_max"), ("los_d_rate", 0, "speed_max")]
            + [(f, j, "rate_max") for f, j in (("los_rate", 1), ("los_rate", 2), ("los_d_rate", 1), ("los_d_rate", 2))]
            + [(f, j, "rate_max") for f in ("omega", "euler_d_rate") for j in range(3)]
            + [(f, j, "accel_max") for f in ("los_d_acc", "euler_d_acc") for j in range(3)])

INPUT_DTYPE = records.INPUT_DTYPE
OUTPUT_DTYPE = records.OUTPUT_DTYPE


@dataclass(frozen=True)
class Constants32:
    """Every float32 constant of the generated step: scalars by name, vectors as float32 arrays."""

    theorem: int
    nodes: int
    scalars: dict[str, np.float32]
    k1: np.ndarray          # (6,)
    k2: np.ndarray          # (6,)
    inv_scale: np.ndarray   # (12,) 1 / input_scale
    centres: np.ndarray     # (nodes,)
    basis_c2: np.ndarray    # (nodes,) 2 c_j
    basis_c3: np.ndarray    # (nodes,) 12 c_j^2 (the squared distance expanded: (S2 - 2 c_j S1) + 12 c_j^2)
    basis_c3d: np.ndarray   # (nodes,) 18 c_j^2: the second network's basis on the 18 inputs [e / s; u_prev]
    gyro: np.ndarray        # (3,) (J1 - J2)/J0, (J2 - J0)/J1, (J0 - J1)/J2
    inertia: np.ndarray     # (3,)
    theta_max: np.ndarray   # (6,) the bound of each column
    theta_max_bits: np.ndarray  # (6,) uint32 bits of theta_max
    pow: PowTab             # |x|^(alpha - 1)

    def __getattr__(self, name: str) -> np.float32:
        try:
            return self.scalars[name]
        except KeyError:
            raise AttributeError(name) from None


def check_period(period: float) -> float:
    if not (isinstance(period, (int, float)) and not isinstance(period, bool) and math.isfinite(period)
            and MIN_PERIOD_S <= period <= MAX_PERIOD_S):
        raise CodegenError(f"control period must be in [{MIN_PERIOD_S:g}, {MAX_PERIOD_S:g}] s, got {period!r}")
    return float(period)


def _c32(value, name: str) -> np.float32:
    return float32_in(float(value), f"rbf-law constant {name}")


def constants32(p: RbfParams, period: float) -> Constants32:
    """The constants of the law, each computed in float64 and rounded to float32 once."""
    period = check_period(period)
    for g, key in ((p.gamma, "gamma"), (p.gamma_delta, "gamma_delta")):
        if period * g * p.lam >= 1.0:
            raise CodegenError(f"period * '{key}' * 'lambda' = {period * g * p.lam:g} must be < 1 "
                               f"(the leakage factor 1 - T gamma lambda would not be positive)")
    alpha32 = np.float32(p.alpha)
    y = np.float32(float(alpha32) - 1.0)
    if not -1.0 < float(y) < 0.0:
        raise CodegenError(f"'alpha' = {p.alpha!r}: alpha - 1 must be in (-1, 0) as float32")
    delta32 = np.float32(p.delta)
    J = [float(np.float32(j)) for j in p.inertia]
    scalars = {
        "k3": p.k3, "alpha": float(alpha32), "delta": float(delta32),
        "eta0": float(alpha32) * float(delta32) ** float(y),          # alpha Delta^(alpha - 1)
        "neg_inv_2s2": -1.0 / (2.0 * p.sigma * p.sigma),
        "a": period * p.gamma, "b": 1.0 - period * p.gamma * p.lam,
        "a_d": period * p.gamma_delta, "b_d": 1.0 - period * p.gamma_delta * p.lam,
        "mass": p.mass, "force_max": p.force_max, "torque_max": p.torque_max,
        # the command's normalisation: the reciprocal of the float32 limit, so |limited output| * it <= 1
        "inv_force_max": 1.0 / float(np.float32(p.force_max)), "inv_torque_max": 1.0 / float(np.float32(p.torque_max)),
        "rho_min": p.rho_min, "rho_max": p.rho_max, "tilt_max": p.tilt_max, "angle_max": ANGLE_MAX,
        "speed_max": p.speed_max, "rate_max": p.rate_max, "accel_max": p.accel_max,
        "pi": float(detmath.PI_HI), "two_pi": 2.0 * float(detmath.PI_HI), "result_max": RESULT_MAX,
        "period": period,
    }
    sc = {k: _c32(v, k) for k, v in scalars.items()}
    gyro = np.array([(J[1] - J[2]) / J[0], (J[2] - J[0]) / J[1], (J[0] - J[1]) / J[2]])
    for i, g in enumerate(gyro):       # 0 allowed (equal inertias); nonzero must be a normal float32
        if g != 0.0:
            _c32(g, f"gyro[{i}]")
    for lim, inv in (("force_max", "inv_force_max"), ("torque_max", "inv_torque_max")):
        # rounding is monotonic: |x| <= limit gives |x * inv| <= fl(limit * inv), which must not exceed 1
        if not np.float32(sc[lim] * sc[inv]) <= np.float32(1.0):
            raise CodegenError(f"'{lim}' * (1 / '{lim}') rounds above 1 in float32")
    theta_max = np.array(p.theta_max, dtype=np.float32)
    inv_scale = np.array([_c32(1.0 / s, f"inv_scale[{i}]") for i, s in enumerate(p.input_scale)], dtype=np.float32)
    return Constants32(
        theorem=p.theorem, nodes=p.nodes, scalars=sc,
        k1=np.array(p.k1, dtype=np.float32), k2=np.array(p.k2, dtype=np.float32), inv_scale=inv_scale,
        centres=p.centres().astype(np.float32),
        basis_c2=(2.0 * p.centres()).astype(np.float32), basis_c3=(12.0 * p.centres() ** 2).astype(np.float32),
        basis_c3d=(18.0 * p.centres() ** 2).astype(np.float32), gyro=gyro.astype(np.float32),
        inertia=np.array(J, dtype=np.float32), theta_max=theta_max,
        theta_max_bits=theta_max.view(np.uint32).copy(), pow=pow_tables(y, np.float32(1.0)))


def params_sha256(p: RbfParams, period: float) -> str:
    """sha256 of the canonical JSON of the parameter file form plus the period."""
    payload = {"params": p.to_mapping(), "period": check_period(period)}
    return hashlib.sha256(json.dumps(payload, sort_keys=True).encode("utf-8")).hexdigest()


def _text(value: float) -> str:
    return f"{value:.9g}"


def _rows_of_8(values, indent: str) -> str:
    return (",\n" + indent * 2).join(", ".join(c_float(v) for v in values[i:i + 8]) for i in range(0, len(values), 8))


def pow_initializer(t: PowTab, indent: str = "    ") -> str:
    """C initializer of <name>_pow_t: {p0, p1}, rows {c, 1/c, c^y, 0}, ek[0..255] (x >= 0 only)."""
    rows = (",\n" + indent * 2).join("{" + ", ".join(c_float(v) for v in r) + "}" for r in t.rows)
    return ("{\n" + indent + "{" + c_float(t.p0) + ", " + c_float(t.p1) + "},\n" + indent + "{\n" + indent * 2
            + rows + "\n" + indent + "},\n" + indent + "{\n" + indent * 2 + _rows_of_8(t.ek[:256], indent) + "\n"
            + indent + "}\n}")


def template_context(p: RbfParams, period: float, name: str) -> dict:
    c = constants32(p, period)
    literal = {k: c_float(v) for k, v in c.scalars.items()}
    vec = {"k1": c.k1, "k2": c.k2, "inv_scale": c.inv_scale, "centres": c.centres, "gyro": c.gyro,
           "inertia": c.inertia}
    items = []
    for k, v in p.to_mapping().items():
        items.append(f"{k} = [{', '.join(_text(x) for x in v)}]" if isinstance(v, list) else f"{k} = {_text(v)}")
    params_lines = [""]
    for item in items:
        if params_lines[-1] and len(params_lines[-1]) + len(item) > 84:
            params_lines.append("")
        params_lines[-1] += (", " if params_lines[-1] else "") + item
    return {
        "name": name, "P": name.upper(), "c": literal,
        "v": {k: [c_float(x) for x in a] for k, a in vec.items()},
        "theorem": c.theorem, "nodes": c.nodes, "weights": 6 * c.nodes,
        "theta_max_bits": [f"0x{int(b):08x}u" for b in c.theta_max_bits],
        "theta_max_text": [_text(x) for x in p.theta_max],
        "theta_max_lit": [c_float(x) for x in c.theta_max],
        "generator_version": GENERATOR_VERSION, "params_sha256": params_sha256(p, period),
        "period_text": _text(period), "params_lines": params_lines,
        "pow": c.pow, "pow_init": pow_initializer(c.pow),
        "status": {k: getattr(records, k) for k in dir(records) if k.startswith("STATUS_")},
        "force_max_text": _text(p.force_max), "torque_max_text": _text(p.torque_max),
        # (2 c_j, 12 c_j^2, 18 c_j^2)
        "basis": [(c_float(a), c_float(b), c_float(d)) for a, b, d in zip(c.basis_c2, c.basis_c3, c.basis_c3d)],
        "bits": {k: f"0x{int(c.scalars[k].view(np.uint32)):08x}u" for k in
                 ("rho_min", "rho_max", "tilt_max", "angle_max", "speed_max", "rate_max", "accel_max")},
        "box": BOX,
    }


def rbf_sources(p: RbfParams, period: float = DEFAULT_PERIOD, name: str = DEFAULT_NAME) -> dict[str, str]:
    """{file name: text}: `<name>.h`, `<name>.c` and the sg_math library they call."""
    check_name(name)
    return unit_sources(TEMPLATES, "rbf", name, template_context(p, period, name))


def emit_rbf(p: RbfParams, out_dir: str | os.PathLike, period: float = DEFAULT_PERIOD,
             name: str = DEFAULT_NAME) -> list[Path]:
    """Generate and write `<name>.h`, `<name>.c`, `sg_math.h`, `sg_math.c` into out_dir."""
    return write_sources(rbf_sources(p, period, name), out_dir)
