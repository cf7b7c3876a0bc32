"""Fit the minimax coefficients of codegen/csrc/sg_math.c (float64 fit, float32 rounding).

Method: discrete minimax over a dense Chebyshev-spaced grid by Lawson's iteratively reweighted
least squares (converges to the Chebyshev/Remez solution), in float64. The coefficients are then
rounded to float32 one at a time, from the lowest order up, re-fitting the still-free higher
ones after each rounding (the rounding error of a low-order coefficient is absorbed by the
others). The printed errors are those of the float32 coefficients evaluated in float64; the
real float32 evaluation error is measured exhaustively by tools/ulp_sweep.py.

Run: python tools/fit_minimax.py               (C literals and max relative error of each fit)
     python tools/fit_minimax.py --tanh-table  (the rows of sg_tanh_tab in sg_math.c)
"""

from __future__ import annotations

import math
import sys
from dataclasses import dataclass
from typing import Callable

import numpy as np

@dataclass
class Fit:
    """f(t) ~ scale(t) * sum_i c_i * t**(step*i) on [lo, hi], relative error weight 1/|f|."""

    name: str
    f: Callable[[np.ndarray], np.ndarray]
    lo: float
    hi: float
    fixed: list[float]  # leading coefficients kept exactly (e.g. 1 and 1/2 in e^r - 1)
    n_free: int
    scale: Callable[[np.ndarray], np.ndarray]
    step: int = 1


def _grid(lo: float, hi: float, n: int = 40001) -> np.ndarray:
    k = np.arange(n)
    return 0.5 * (lo + hi) + 0.5 * (hi - lo) * np.cos(np.pi * k / (n - 1))


def _lawson(a: np.ndarray, b: np.ndarray, iters: int = 400, robust: bool = False) -> np.ndarray:
    """min_c max_i |a_i . c - b_i| by Lawson's reweighting; rows are already error-weighted.

    robust=True (the tanh table, whose fits are nearly exact): the weights are floored at 1e-3
    of the mean so that errors at float64 noise level do not collapse them onto a few points,
    and the best iterate by max error is returned instead of the last.
    """
    w = np.full(len(b), 1.0 / len(b))
    best, best_err = None, np.inf
    c = np.zeros(a.shape[1])
    for _ in range(iters):
        sw = np.sqrt(w)
        c = np.linalg.lstsq(a * sw[:, None], b * sw, rcond=None)[0]
        err = np.abs(a @ c - b)
        if err.max() < best_err:
            best, best_err = c, err.max()
        w = w * (err + 1e-300)
        w /= w.sum()
        if robust:
            w = np.maximum(w, 1e-3 / len(b))
            w /= w.sum()
    return best if robust else c


def _design(fit: Fit, t: np.ndarray, n_fixed: int, n_terms: int) -> np.ndarray:
    cols = [fit.scale(t) * t ** (fit.step * i) for i in range(n_fixed, n_terms)]
    return np.stack(cols, axis=1)


def solve(fit: Fit, grid: int = 40001, iters: int = 400) -> tuple[list[float], float]:
    """Return float32-representable coefficients (fixed + free) and their max relative error."""
    t = _grid(fit.lo, fit.hi, grid)
    t = t[t != 0.0]
    f = fit.f(t)
    w = 1.0 / np.abs(f)
    coeffs = list(fit.fixed)
    n_terms = len(fit.fixed) + fit.n_free
    while len(coeffs) < n_terms:
        known = sum(c * fit.scale(t) * t ** (fit.step * i) for i, c in enumerate(coeffs))
        a = _design(fit, t, len(coeffs), n_terms) * w[:, None]
        c = _lawson(a, (f - known) * w, iters)
        coeffs.append(float(np.float32(c[0])))
    approx = sum(c * fit.scale(t) * t ** (fit.step * i) for i, c in enumerate(coeffs))
    return coeffs, float(np.max(np.abs(approx - f) * w))


def _expm1(r):
    return np.expm1(r)


def _log_r(z):
    # 2 atanh(s)/s - 2 = 2 sum_{n>=1} z^n / (2n+1), summed as a series to avoid cancellation
    return sum(2.0 * z**n / (2 * n + 1) for n in range(30, 0, -1))


def _sin(r):
    return np.sin(r)


def _cos_tail(z):
    # cos r - 1 + z/2 = sum_{n>=2} (-z)^n / (2n)!, as a series to avoid cancellation
    return sum((-z) ** n / math.factorial(2 * n) for n in range(20, 1, -1))


def _asin(x):
    return np.arcsin(x)


def _atan(x):
    return np.arctan(x)


FITS = [
    # exp: e^r - 1 = r * (1 + r/2 + c2 r^2 + ...), |r| <= ln2/2 (+ margin)
    Fit("exp_q", _expm1, -0.3470, 0.3470, [1.0, 0.5], 4, lambda t: t),
    # log: R(z) = 2 atanh(s)/s - 2 = z * (c1 + c2 z + ...), z = s^2, s <= (sqrt2-1)/(sqrt2+1)
    Fit("log_R", _log_r, 1e-12, 0.02944, [], 3, lambda t: t),
    # sin: sin r = r + r^3 (s3 + s5 r^2 + ...), |r| <= pi/4 (+ margin)
    Fit("sin", _sin, 1e-9, 0.7860, [1.0], 3, lambda t: t, step=2),
    # cos: cos r - 1 + r^2/2 = r^4 (c4 + c6 r^2 + ...), written over z = r^2
    Fit("cos_tail", _cos_tail, 1e-12, 0.6178, [], 3, lambda t: t * t),
    # asin on [0, 1/2]: x + x^3 (a3 + a5 x^2 + ...)
    Fit("asin", _asin, 1e-9, 0.5001, [1.0], 5, lambda t: t, step=2),
    # atan on [0, 1]: x + x^3 (b3 + b5 x^2 + ...)
    Fit("atan", _atan, 1e-9, 1.0, [1.0], 9, lambda t: t, step=2),
]


# tanh table: |x| in [2^-12, 9) cut into 8 intervals per binade (exponent + 3 mantissa bits of
# the float, so the C indexes it with two shifts); on each, tanh(c + t) ~ c0 + c1 t + ... + c4 t^4
# around the float32 midpoint c, fitted for relative error like the fits above.
TANH_M, TANH_EMIN, TANH_MAX, TANH_DEG = 3, -12, 9.0, 4


def tanh_intervals() -> list[tuple[float, float]]:
    """[lo, hi) of each table interval, in index order (index = bits(a) >> 20 - first)."""
    first = (127 + TANH_EMIN) << TANH_M
    out = []
    while True:
        u = (first + len(out)) << (23 - TANH_M)
        lo, hi = (float(np.uint32(v).view(np.float32)) for v in (u, u + (1 << (23 - TANH_M))))
        if lo >= TANH_MAX:
            return out
        out.append((lo, hi))


def _tanh_coeffs(c: float, h: float, u: np.ndarray, refit: bool) -> list[float]:
    """Minimax c0..c4 of tanh(c + h u) in the scaled variable u (unknowns c_i h^i), rounded to
    float32 low order first; refit=True re-solves the higher ones after each rounding."""
    f = np.tanh(c + h * u)
    w = 1.0 / np.abs(f)
    coeffs: list[float] = []
    d = None
    for k in range(TANH_DEG + 1):
        if refit or d is None:
            known = sum(ci * (h * u) ** i for i, ci in enumerate(coeffs))
            a = np.stack([u**i for i in range(k, TANH_DEG + 1)], axis=1) * w[:, None]
            d = list(_lawson(a, (f - known) * w, 150, robust=True))
        coeffs.append(float(np.float32(d.pop(0) / h**k)))
    return coeffs


def _tanh_row_error(row: list[float], lo: float, hi: float) -> float:
    """Max error in ulp of the float32 Horner evaluation of one row over ~4000 arguments."""
    ulo, uhi = (int(np.float32(v).view(np.uint32)) for v in (lo, hi))
    a = np.arange(ulo, uhi, max(1, (uhi - ulo) // 4000), dtype=np.uint32).view(np.float32)
    t = a - np.float32(row[0])
    p = np.full_like(t, np.float32(row[-1]))
    for ci in row[-2:0:-1]:
        p = p * t + np.float32(ci)
    ref = np.tanh(a.astype(np.float64))
    return float(np.max(np.abs(p - ref) / 2.0 ** (np.floor(np.log2(ref)) - 23)))


def tanh_row(lo: float, hi: float) -> list[float]:
    """[c, c0, ..., c4] of one interval around its float32 midpoint c: of the two roundings
    (with and without re-fitting), the one whose float32 evaluation is more accurate."""
    c = float(np.float32(0.5 * (lo + hi)))
    h = 0.5 * (hi - lo)
    u = _grid((lo - c) / h, (hi - c) / h, 2001)
    rows = [[c, *_tanh_coeffs(c, h, u, refit)] for refit in (False, True)]
    return min(rows, key=lambda row: _tanh_row_error(row, lo, hi))


def tanh_table() -> list[list[float]]:
    return [tanh_row(lo, hi) for lo, hi in tanh_intervals()]


def c_literal(v: float) -> str:
    """A float32 value as an exact C hex-float literal."""
    mant, exp = float(np.float32(v)).hex().split("p")
    return mant.rstrip("0").rstrip(".") + "p" + exp + "f"


def main() -> None:
    if "--tanh-table" in sys.argv:
        for row in tanh_table():
            print("    {" + ", ".join(c_literal(v) for v in row) + "},")
        return
    for fit in FITS:
        coeffs, err = solve(fit)
        print(f"{fit.name}: max rel err (float32 coeffs, float64 eval) = {err:.3e}")
        for i, c in enumerate(coeffs):
            print(f"  c{i} = {c_literal(c):>22}  /* {np.float32(c)!r} */")


if __name__ == "__main__":
    main()
