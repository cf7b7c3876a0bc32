"""C emitter of paper 004's GP takeover law (docs/gp-takeover.md section 11): the law's parameter file
(gains, torque limit, prior inertia) and its trained GP artifact -> `<name>.h/.c`.

The GP's float32 arrays are the artifact's `flight` arrays (re-derived and checked on load), laid out
for the step's loops: A' = sigma_f^2 L^-1 packed by rows of its lower triangle; R_k^T packed by
columns of R_k's lower triangle with the three axes interleaved (`rt[p][k]`); the means interleaved
(`mw[j][k]`). The law's constants are computed in float64 and rounded to float32 once, here, for the
C (hex-float literals) and the golden twin (codegen/units/gp/golden.py reads `constants32`). Output
is a pure function of (parameters, name, generator version): byte-identical sources.

Float32 safety is checked here, before any C is written: with every kernel value in (0, 1], the
projection w = A' k, the per-axis sums R_k^T w, their squares and the means stay finite for every
input of the valid box (the bounds below), so the step can produce no Inf or NaN.
"""
from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from codegen import GENERATOR_VERSION
from codegen.cgen import c_float, check_name, unit_sources, write_sources
from codegen.errors import CodegenError
from codegen.units.gp import records
from codegen.units.gp.params import GpLawParams
from codegen.values import float32_in

TEMPLATES = Path(__file__).with_name("templates")
DEFAULT_NAME = "gp"
# |w_i| <= W_MAX for every kernel vector in (0, 1]^M (row sums of |A'|); then |w_i|^2 and the sums of
# M <= 200 squares are finite, and |(R_k^T w)_i| <= W_MAX as well (column sums of |R_k| times W).
W_MAX = 1e17
MEAN_MAX = 1e30          # |mu_k| <= mu_scale_k * W * sum_j |m_kj|


@dataclass(frozen=True)
class Constants32:
    """Every float32 constant of the generated step."""

    m: int                   # inducing points M
    g: np.ndarray            # (6,) 1 / (input scale * lengthscale)
    zt: np.ndarray           # (M, 6) scaled inducing inputs
    c: np.ndarray            # (M,) the folded omega-dot part of the exponent (<= 0)
    a: np.ndarray            # (P,) A' packed by rows: A'[i][j], j <= i
    rt: np.ndarray           # (P, 3) R_k[j][i] for i = 0.., j = i..M-1 (columns of R_k), axes interleaved
    mw: np.ndarray           # (M, 3) whitened means m_kj, axes interleaved
    kxx: np.float32          # sigma_f^2 (normalised prior variance)
    inv_kxx: np.float32
    mu_scale: np.ndarray     # (3,) s_y, N*m
    var_scale: np.ndarray    # (3,) s_y^2
    prior_var: np.ndarray    # (3,) fl(var_scale * kxx): the variance outside the valid box
    k1: np.float32
    dk1: np.float32          # k1_bar - k1
    k1_bar: np.float32
    k2: np.float32
    dk2: np.float32
    k2_bar: np.float32
    torque_max: np.float32
    inertia: np.ndarray      # (3, 3) J_s
    box: dict                # float32 limits of the valid box by name

    @property
    def p(self) -> int:
        return self.m * (self.m + 1) // 2


def _c32(value, name: str, **bounds) -> np.float32:
    return float32_in(float(value), f"gp-law constant {name}", **bounds)


def _column_packed(R: np.ndarray) -> np.ndarray:
    """R (3, M, M) lower -> (P, 3): for i = 0..M-1, j = i..M-1: R_k[j][i]."""
    m = R.shape[-1]
    return np.stack([R[:, j, i] for i in range(m) for j in range(i, m)])


def _unpacked_rows(p: np.ndarray, m: int) -> np.ndarray:
    T = np.zeros((m, m), dtype=np.float64)
    T[np.tril_indices(m)] = p
    return T


def check_magnitudes(fl: dict, m: int) -> None:
    """Refuse arrays whose float32 evaluation could overflow in the valid box (module docstring)."""
    A = np.abs(_unpacked_rows(fl["A"].astype(np.float64), m))
    w_max = float(A.sum(axis=1).max())
    if not w_max <= W_MAX:
        raise CodegenError(f"GP artifact: row sums of |sigma_f^2 L^-1| reach {w_max:.3g}, above {W_MAX:g} "
                           "(K_ZZ too ill-conditioned for float32 evaluation)")
    for k in range(3):
        R = np.abs(_unpacked_rows(fl["R"][k].astype(np.float64), m))
        e_max = w_max * float(R.sum(axis=0).max())
        if not e_max <= W_MAX:
            raise CodegenError(f"GP artifact: axis {k}: |R_k^T w| may reach {e_max:.3g}, above {W_MAX:g}")
        sum_max = w_max * float(np.abs(fl["m"][k].astype(np.float64)).sum())     # m_k^T w, summed before scaling
        mu_max = float(fl["mu_scale"][k]) * sum_max
        if not (sum_max <= MEAN_MAX and mu_max <= MEAN_MAX):
            raise CodegenError(f"GP artifact: axis {k}: the mean's sum may reach {sum_max:.3g} (scaled "
                               f"{mu_max:.3g} N*m), above {MEAN_MAX:g}")


def schedule_scale(kxx: np.float32, inv_kxx: np.float32) -> np.float32:
    """1 / k_xx as the step multiplies by it: the artifact's value, lowered by an ulp while
    fl(k_xx * it) > 1 (about 5 % of float32 values of k_xx), so that s = v / k_xx <= 1 for v <= k_xx."""
    inv = np.float32(inv_kxx)
    while np.float32(kxx * inv) > np.float32(1.0):
        inv = np.nextafter(inv, np.float32(0.0))
    return inv


def constants32(p: GpLawParams) -> Constants32:
    """The step's constants: the artifact's flight arrays re-laid, the law's values rounded once."""
    fl = p.gp.flight
    m = p.n_inducing
    if m < 2:
        raise CodegenError(f"unit gp: needs at least 2 inducing points, the artifact has {m}")
    check_magnitudes(fl, m)
    R = np.stack([_unpacked_rows(fl["R"][k].astype(np.float64), m) for k in range(3)])
    kxx = np.float32(fl["kxx"])
    var_scale = fl["var_scale"].astype(np.float32)
    with np.errstate(over="ignore"):
        prior_var = (var_scale * kxx).astype(np.float32)
    if not np.all(np.isfinite(prior_var)):
        raise CodegenError("GP artifact: output_scale^2 * sigma_f^2 overflows float32")
    k1, k1_bar = _c32(p.k1, "k1"), _c32(p.k1_bar, "k1_bar")
    k2, k2_bar = _c32(p.k2, "k2"), _c32(p.k2_bar, "k2_bar")
    box = {"q_max": records.Q_MAX, "norm2_min": records.NORM2_MIN, "norm2_max": records.NORM2_MAX,
           "rate_max": records.RATE_MAX, "momentum_max": records.MOMENTUM_MAX,
           "exponent_min": records.EXPONENT_MIN}
    return Constants32(
        m=m, g=fl["g"].astype(np.float32), zt=fl["zt"].astype(np.float32), c=fl["c"].astype(np.float32),
        a=fl["A"].astype(np.float32), rt=_column_packed(R).astype(np.float32),
        mw=np.ascontiguousarray(fl["m"].astype(np.float32).T), kxx=kxx,
        inv_kxx=schedule_scale(kxx, np.float32(fl["inv_kxx"])),
        mu_scale=fl["mu_scale"].astype(np.float32), var_scale=var_scale, prior_var=prior_var,
        k1=k1, dk1=_c32(float(p.k1_bar) - float(p.k1), "k1_bar - k1", low=0.0), k1_bar=k1_bar,
        k2=k2, dk2=_c32(float(p.k2_bar) - float(p.k2), "k2_bar - k2", low=0.0), k2_bar=k2_bar, torque_max=_c32(p.torque_max, "torque_max"),
        inertia=np.array(p.inertia, dtype=np.float64).astype(np.float32),
        box={k: _c32(v, k) for k, v in box.items()})


def _bits(x: np.float32) -> str:
    return f"0x{int(np.float32(x).view(np.uint32)):08x}u"


def _rows(values, per_row: int = 6, indent: str = "    ") -> str:
    """C initializer body: a 1-D array as lines of per_row values, a 2-D one as one braced row per line."""
    a = np.asarray(values, dtype=np.float32)
    if a.ndim == 2:
        return (",\n" + indent).join("{" + ", ".join(c_float(v) for v in row) + "}" for row in a)
    flat = [c_float(v) for v in a.reshape(-1)]
    return (",\n" + indent).join(", ".join(flat[i:i + per_row]) for i in range(0, len(flat), per_row))


def template_context(p: GpLawParams, name: str) -> dict:
    c = constants32(p)
    a = p.gp.arrays
    return {
        "name": name, "P": name.upper(), "m": c.m, "p": c.p,
        "generator_version": GENERATOR_VERSION, "params_sha256": p.sha256(), "artifact_sha256": p.gp.sha256,
        "g": [c_float(v) for v in c.g],
        "zt": _rows(c.zt, 6, "        "), "c_init": _rows(c.c, 6, "        "), "a_init": _rows(c.a, 6, "        "),
        "rt_init": _rows(c.rt, 6, "        "), "mw_init": _rows(c.mw, 6, "        "),
        "kxx": c_float(c.kxx), "inv_kxx": c_float(c.inv_kxx),
        "mu_scale": [c_float(v) for v in c.mu_scale], "var_scale": [c_float(v) for v in c.var_scale],
        "prior_var": [c_float(v) for v in c.prior_var],
        "k1": c_float(c.k1), "dk1": c_float(c.dk1), "k1_bar": c_float(c.k1_bar),
        "k2": c_float(c.k2), "dk2": c_float(c.dk2), "k2_bar": c_float(c.k2_bar),
        "torque_max": c_float(c.torque_max), "J": [[c_float(v) for v in row] for row in c.inertia],
        "box": {k: c_float(v) for k, v in c.box.items()}, "box_bits": {k: _bits(v) for k, v in c.box.items()},
        "status": {k: getattr(records, k) for k in dir(records) if k.startswith("STATUS_")},
        "text": {"k1": f"{p.k1:.9g}", "k1_bar": f"{p.k1_bar:.9g}", "k2": f"{p.k2:.9g}", "k2_bar": f"{p.k2_bar:.9g}",
                 "torque_max": f"{p.torque_max:.9g}", "outputscale": f"{a.outputscale:.9g}",
                 "jitter": f"{a.jitter:.3g}", "cond": f"{p.gp.conditioning.cond:.4g}"},
    }


def gp_sources(p: GpLawParams, name: str = DEFAULT_NAME) -> dict[str, str]:
    """{file name: text}: `<name>.h`, `<name>.c` and the sg_math library they use."""
    check_name(name)
    return unit_sources(TEMPLATES, "gp", name, template_context(p, name))


def emit_gp(p: GpLawParams, out_dir: str | os.PathLike, name: str = DEFAULT_NAME) -> list[Path]:
    """Generate and write `<name>.h`, `<name>.c`, `sg_math.h`, `sg_math.c` into out_dir."""
    return write_sources(gp_sources(p, name), out_dir)
