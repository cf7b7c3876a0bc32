"""The tanh law's own power tables: K·x^y for a generation-time exponent y (|y| < 1) and scale K.

The C (templates/tanh.c.j2, `<name>_powK*`) and the golden twin (golden.pow_scaled) evaluate, for
the bits u of a float32 x (the sign bit included):

    x = ±2^(E - 127) z, z in [1, 2), E = (u >> 23) & 255 (the biased exponent)
    row = rows[(u >> SHIFT) & (N - 1)] = {c, 1/c, c^y, 0}   (N intervals of z, c their midpoints)
    z = bits((u & 0x7fffff) | 0x3f800000)
    r = (z - c) (exact, Sterbenz) * (1/c)                   |r| <= 2^-8 for N = 128, 2^-9 for 256
    q = r (p0 + r p1)               p0 = y, p1 = y (y - 1) / 2: (1 + r)^y - 1 to the quadratic term
    s = c^y * ek[u >> 23]           ek[E] = K 2^(y (E - 127)), ek[256 + E] = -ek[E] (the sign of x), ek[0] = 0
    result = s + s q                = sign(x) K |x|^y

sg_powf_const (sg_math.h) has 32 intervals and a cubic; here N is 128 or 256 (the smallest whose
truncation |y (y - 1) (y - 2) / 6| r^3 stays below 2^-27) and the scale K and the sign of x are in
the 2^(y k) table, so there is no multiply by K, no sign select and no range test: every u gives
a finite value (ek[0] = ±0: x = ±0 and subnormals give ±0, sg_powf_const's +0 there; NaN and Inf
a finite value nobody reads, see the template). Error <= 2.5 ulp of K|x|^y for normal x (tests/codegen/units/tanh).

Every table entry is the float64 (Decimal, 40 digits: byte-identical on every host) value rounded
once to float32.
"""
from __future__ import annotations

import functools
import math
from dataclasses import dataclass

import numpy as np

from codegen.detmath import decimal_pow

F32 = np.float32
Z0 = 0x3F800000            # bits of the smallest z (1.0)
TRUNCATION_MAX = 2.0 ** -27


@dataclass(frozen=True)
class PowTab:
    y: np.float32
    scale: np.float32
    p0: np.float32
    p1: np.float32
    shift: int               # row index (i >> shift) & (n - 1)
    rows: np.ndarray         # (n, 4) float32: c, 1/c, c^y, 0
    ek: np.ndarray           # (512,) float32: [E] K 2^(y (E - 127)), [256 + E] its negation, [0] and [256] ±0

    @property
    def n(self) -> int:
        return self.rows.shape[0]


def intervals_for(y: float) -> int:
    """128, or 256 when the quadratic's truncation would exceed 2^-27 relative with 128."""
    c3 = abs(y * (y - 1.0) * (y - 2.0) / 6.0)
    return 128 if c3 * (2.0 ** -8) ** 3 <= TRUNCATION_MAX else 256


@functools.lru_cache(maxsize=16)
def _tables(ybits: int, kbits: int) -> PowTab:
    y32 = np.uint32(ybits).view(F32)
    k32 = np.uint32(kbits).view(F32)
    y, k = float(y32), float(k32)
    if not (math.isfinite(y) and 0.0 < abs(y) < 1.0 and math.isfinite(k) and k > 0.0):
        raise ValueError(f"pow tables: need 0 < |y| < 1 and K > 0 finite, got y = {y!r}, K = {k!r}")
    n = intervals_for(y)
    width = 0x800000 // n  # bits of z per interval (z spans 0x800000 bit patterns)
    shift = int(math.log2(width))
    rows = np.zeros((n, 4), dtype=F32)
    for j in range(n):
        cbits = Z0 + j * width + width // 2
        c = float(np.uint32(cbits).view(F32))
        rows[j, 0] = F32(c)
        rows[j, 1] = F32(1.0 / c)  # float64 division, rounded once (1/c is not exact)
        rows[j, 2] = F32(float(decimal_pow(c, y)))
    ek = np.zeros(512, dtype=F32)
    top = float(np.finfo(F32).max)
    for e in range(1, 256):
        v = F32(min(float(decimal_pow(2.0, y * (e - 127), k)), top))
        ek[e] = v
        ek[256 + e] = -v
    ek[256] = F32(-0.0)
    p0 = y32
    p1 = F32(y * (y - 1.0) / 2.0)
    return PowTab(y32, k32, p0, p1, shift, rows, ek)


def pow_tables(y, scale) -> PowTab:
    """The tables for the float32 exponent y and the float32 scale K."""
    return _tables(int(F32(y).view(np.uint32)), int(F32(scale).view(np.uint32)))
