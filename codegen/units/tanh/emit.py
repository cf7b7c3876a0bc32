"""C emitter of paper 000's tanh saturation law: parameters + control period -> `<name>.h/.c`.

The parameters (codegen.tanh_params) are baked in as float32 hex-float constants; the float64
values come from the same formulas as host.control.tanh_law.compile_constants and are rounded to
float32 once, here, for both the C and the golden twin (codegen.golden_tanh reads
`constants32`). Output is a pure function of (parameters, period, name, generator version):
byte-identical sources for the same inputs. The deterministic math library is copied next to
the law (codegen.cgen.math_sources).
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
from codegen.values import float32_in
from codegen.detmath import TANH_COLS, TANH_HALF, tanh_rows
from codegen.units.tanh.powtab import PowTab, pow_tables
from codegen.units.tanh.params import TanhParams, derived_constants

TEMPLATES = Path(__file__).with_name("templates")
DEFAULT_NAME = "tanh"
DEFAULT_PERIOD = 0.1  # s, the paper-000 example's sampled flight version

# The C structs of templates/tanh.h.j2 as numpy records (4-byte fields: no padding).
INPUT_DTYPE = np.dtype([("R_c", "<f4", (9,)), ("w_c", "<f4", (3,)), ("R_t", "<f4", (9,)), ("w_t", "<f4", (3,)),
                        ("wdot_t", "<f4", (3,))])
STATE_DTYPE = np.dtype([("varpi", "<f4", (3,))])
OUTPUT_DTYPE = np.dtype([("torque", "<f4", (3,)), ("x1", "<f4", (3,)), ("x2", "<f4", (3,)), ("varpi", "<f4", (3,)),
                         ("status", "<u4")])


@dataclass(frozen=True)
class Constants32:
    """Every float32 constant of the generated step, by template name (scalars and J, J_inv)."""

    scalars: dict[str, np.float32]
    J: np.ndarray       # (9,) float32, row-major
    J_inv: np.ndarray   # (9,) float32, row-major

    def __getattr__(self, name: str) -> np.float32:
        try:
            return self.scalars[name]
        except KeyError:
            raise AttributeError(name) from None


MIN_PERIOD_S, MAX_PERIOD_S = 1e-4, 10.0   # T is baked in as a float32 and multiplies rates


def check_period(period: float) -> float:
    if not (isinstance(period, (int, float)) and math.isfinite(period) and MIN_PERIOD_S <= period <= MAX_PERIOD_S):
        raise CodegenError(f"control period must be in [{MIN_PERIOD_S:g}, {MAX_PERIOD_S:g}] s, got {period!r}")
    return float(period)


def constants32(p: TanhParams, period: float) -> Constants32:
    """The float64 constants of the law, each rounded to float32 once."""
    period = check_period(period)
    d = derived_constants(p)
    constants = {
        "nk1": -p.k1, "nk2": -p.k2, "k2": p.k2, "k3": p.k3,
        "eps1": p.eps1, "eps2": p.eps2, "eps3": p.eps3,
        "nbeta1": -p.beta1, "beta2": p.beta2, "gamma": p.gamma, "gamma_m1": p.gamma - 1.0, "eta": p.eta,
        "r1": d["r1"], "r2": d["r2"], "r2x2": 2.0 * d["r2"],
        "br1": p.beta2 * d["r1"], "br2": p.beta2 * d["r2"], "br2x2": 2.0 * p.beta2 * d["r2"],
        "lam": p.lam, "nlam2": -2.0 * p.lam,
        "k4": p.k4, "k5": p.k5, "d_max": p.d_max, "delta_reg": p.delta_reg, "n1": p.n1,
        "ua_gain": d["ua_gain"], "ua_inner": d["ua_inner_scale"],
        "q0min_sq": p.q0_min ** 2, "q0min_sq4": 4.0 * p.q0_min ** 2,
        "period": period, "limit": p.varpi_limit,
    }
    # derived constants follow the parameters' float32 rule (codegen.values): none may overflow,
    # none nonzero may become 0 or a subnormal
    scalars = {k: _constant32(v, k) for k, v in constants.items()}
    J = np.array([_constant32(v, f"J[{i}]") for i, v in enumerate(np.ravel(d["J"]))], dtype=np.float32)
    J_inv = np.array([_constant32(v, f"J_inv[{i}]") for i, v in enumerate(np.ravel(d["J_inv"]))], dtype=np.float32)
    return Constants32(scalars, J, J_inv)


def _constant32(value, name: str) -> np.float32:
    return float32_in(float(value), f"tanh-law constant {name}")


def params_sha256(p: TanhParams, period: float) -> str:
    """sha256 of the canonical JSON of the parameter file form plus the period."""
    payload = {"params": p.to_mapping(), "period": check_period(period)}
    return hashlib.sha256(json.dumps(payload, sort_keys=True).encode("utf-8")).hexdigest()


def _text(value: float) -> str:
    return f"{value:.9g}"


def sqrt_gt_threshold(n1: np.float32) -> np.float32:
    """The largest float32 d with sqrtf(d) <= n1 (n1 > 0 finite): IEEE sqrt is correctly rounded
    and monotone, so sqrtf(d) > n1 <=> d > this, for every float32 d (NaN: both false)."""
    n1 = np.float32(n1)
    with np.errstate(over="ignore"):
        d = np.minimum(np.float32(n1 * n1), np.finfo(np.float32).max)
        while np.sqrt(d) > n1:
            d = np.nextafter(d, np.float32(0.0))
        while d < np.finfo(np.float32).max and np.sqrt(np.nextafter(d, np.float32(np.inf))) <= n1:
            d = np.nextafter(d, np.float32(np.inf))
    return np.float32(d)


def equal_gains(c: Constants32) -> bool:
    """k1 = k2 = k3 (as float32): the torque (17) is then -k1 ((tanh a + tanh b) + tanh c)."""
    return bool(c.k2 == c.k3 and c.nk1 == -c.k2)


def shaping_pow(c: Constants32) -> PowTab:
    """beta2 |x|^(gamma - 1) of f (11) (gamma - 1 the float32 constant)."""
    return pow_tables(c.gamma_m1, c.beta2)


def compensation_pow(c: Constants32) -> PowTab:
    """||J^-1|| d_max sig(delta)^gamma / n1^gamma of u_a (20)."""
    return pow_tables(c.gamma, c.ua_inner)


def _rows_of_8(values, indent: str) -> str:
    """Float32 values as hex-float C literals, 8 per line."""
    return (",\n" + indent * 2).join(", ".join(c_float(v) for v in values[i:i + 8]) for i in range(0, len(values), 8))


def pow_initializer(t: PowTab, indent: str = "    ", n_ek: int = 512) -> str:
    """C initializer of a <name>_pow_*_t: {p0, p1}, the rows {c, 1/c, c^y, 0}, the first n_ek entries of
    ek (8 per line; 256 where x >= 0)."""
    rows = (",\n" + indent * 2).join("{" + ", ".join(c_float(v) for v in r) + "}" for r in t.rows)
    ek = _rows_of_8(t.ek[:n_ek], indent)
    return ("{\n" + indent + "{" + c_float(t.p0) + ", " + c_float(t.p1) + "},\n" + indent + "{\n" + indent * 2
            + rows + "\n" + indent + "},\n" + indent + "{\n" + indent * 2 + ek + "\n" + indent + "}\n}")


def log_initializer(indent: str = "    ") -> str:
    """C initializer of <name>_log_t: sg_logf_tab's r^4 and r^2 coefficients, sg_logf_tab_rows
    {c, 1/c, ln c, 0}, k * LN2_HI and k * LN2_LO (float32 products) for k = E - 127, E = 0 .. 127."""
    rows = np.asarray(detmath._LT_ROWS, dtype=np.float32)  # sg_logf_tab_rows (float32 values)
    assert np.array_equal(rows.astype(np.float64), detmath._LT_ROWS)
    k = (np.arange(128) - 127).astype(np.float32)
    kh = (k * detmath.LN2_HI).astype(np.float32)
    kl = (k * detmath.LN2_LO).astype(np.float32)
    body = (",\n" + indent * 2).join("{" + ", ".join(c_float(v) for v in (*r, np.float32(0.0))) + "}" for r in rows)
    return ("{\n" + indent + c_float(detmath.LOGF_TAB_C4) + ",\n" + indent
            + c_float(detmath.LOGF_TAB_C2) + ",\n" + indent + "{\n" + indent * 2 + body + "\n"
            + indent + "},\n" + indent + "{\n" + indent * 2 + _rows_of_8(kh, indent) + "\n" + indent + "},\n" + indent
            + "{\n" + indent * 2 + _rows_of_8(kl, indent) + "\n" + indent + "}\n}")


def template_context(p: TanhParams, period: float, name: str) -> dict:
    c = constants32(p, period)
    if not c.eta >= np.finfo(np.float32).tiny:
        # f's power branch (|x| > eta) reads |x| as a positive normal float: no slow path there
        raise CodegenError(f"eta = {p.eta!r} is below the smallest normal float32 (1.18e-38)")
    literal = {k: c_float(v) for k, v in c.scalars.items()}
    pow_f, pow_u = shaping_pow(c), compensation_pow(c)
    literal["n1_dsq"] = c_float(sqrt_gt_threshold(c.n1))
    literal["J"] = [c_float(v) for v in c.J]
    literal["J_inv"] = [c_float(v) for v in c.J_inv]
    items = [f"{k} = {_text(v)}" if not isinstance(v, list) else
             f"{k} = {[[_text(x) for x in row] for row in v]}".replace("'", "")
             for k, v in p.to_mapping().items()]
    params_lines = [""]
    for item in items:  # comment lines of at most ~90 characters
        if params_lines[-1] and len(params_lines[-1]) + len(item) > 84:
            params_lines.append("")
        params_lines[-1] += (", " if params_lines[-1] else "") + item
    return {
        "name": name, "P": name.upper(), "c": literal,
        "generator_version": GENERATOR_VERSION, "params_sha256": params_sha256(p, period),
        "period": c_float(c.period), "period_text": _text(period),
        "limit_text": _text(p.varpi_limit), "q0_min_text": _text(p.q0_min),
        "torque_bound_text": _text(p.k1 + p.k2 + p.k3), "params_lines": params_lines,
        "pow_f": pow_f, "pow_u": pow_u,
        "pow_f_init": pow_initializer(pow_f, n_ek=256), "pow_u_init": pow_initializer(pow_u),
        "eta_bits": f"0x{int(c.eta.view(np.uint32)):08x}", "equal_gains": equal_gains(c),
        "log_init": log_initializer(),
        "tanh_rows": [[c_float(v) for v in row] for row in tanh_rows()],
        "tanh_half": TANH_HALF, "tanh_cols": TANH_COLS,
    }


def tanh_sources(p: TanhParams, period: float = DEFAULT_PERIOD, name: str = DEFAULT_NAME) -> dict[str, str]:
    """{file name: text}: `<name>.h`, `<name>.c` and the sg_math library they call."""
    check_name(name)
    return unit_sources(TEMPLATES, "tanh", name, template_context(p, period, name))


def emit_tanh(p: TanhParams, out_dir: str | os.PathLike, period: float = DEFAULT_PERIOD,
              name: str = DEFAULT_NAME) -> list[Path]:
    """Generate and write `<name>.h`, `<name>.c`, `sg_math.h`, `sg_math.c` into out_dir."""
    return write_sources(tanh_sources(p, period, name), out_dir)
