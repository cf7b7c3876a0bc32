"""numpy float32 twin of codegen/csrc/sg_math.c, operation for operation, bit for bit.

Each function mirrors its C counterpart: the same IEEE single-precision operations in the same
order (numpy float32 ufuncs round each operation once, like SSE and FPv4-SP without FMA), the
C branches as masks (np.where keeps every lane's arithmetic identical to the branch it takes),
and bit reinterpretation through .view(np.uint32) like the C union. Inputs are float32 arrays or
scalars (converted with np.asarray(..., np.float32)); outputs are float32 arrays of the same
shape. Never np.tanh/np.exp/np.log/np.sin/...: their SIMD versions differ from any C code.

Warnings are silenced inside each function: lanes whose result is discarded by np.where (or
the IEEE special values themselves) legitimately produce inf/nan intermediates.
"""

from __future__ import annotations

import decimal
import functools
import math
import re
from typing import NamedTuple
from pathlib import Path

import numpy as np

from codegen.cgen import c_float

F32 = np.float32
U32 = np.uint32

#: sin/cos are accurate (docs/math.md) for |x| <= TRIG_MAX_ARG; beyond it finite in [-1, 1].
TRIG_MAX_ARG = F32(8192.0)

#: Published maximum error in ulp (measured ones in docs/math.md are below); the tests assert them.
ULP_BOUND = {"tanhf": 2.0, "expf": 2.0, "logf": 2.0, "sinf": 2.0, "cosf": 2.0,
             "asinf": 2.0, "atan2f": 3.0, "sqrtf": 0.5}

#: powf_pos(x, y) = expf(y * logf(x)): error <= POW_ULP_BASE + POW_ULP_PER_LOG * |y ln x| ulp
#: (the relative error of y*ln x, <= 1.34 * 2^-23, becomes an absolute error in the exponent).
POW_ULP_BASE = 1.5
POW_ULP_PER_LOG = 2.7


def _f32(x) -> np.ndarray:
    return np.asarray(x, dtype=F32)


def _as_u32(x: np.ndarray) -> np.ndarray:
    return np.asarray(x, dtype=F32).view(U32)  # same item size: works for 0-d and strided


def _as_f32(u: np.ndarray) -> np.ndarray:
    return np.asarray(u, dtype=U32).view(F32)


def _check(y: np.ndarray) -> np.ndarray:
    assert y.dtype == F32, y.dtype
    return y


def _horner(r: np.ndarray, coeffs: tuple[float, ...]) -> np.ndarray:
    """p = c[0]; p = p*r + c[i] ... in float32, the C's fixed Horner order."""
    p = np.full_like(r, F32(coeffs[0]))
    for c in coeffs[1:]:
        p = p * r + F32(c)
    return p


# ---------------------------------------------------------------- tanh

CSRC = Path(__file__).resolve().parent / "csrc"
_TANH_M = 3
_TANH_FIRST = (127 - 12) << _TANH_M
_TANH_TINY_BITS = 0x39800000  # 2^-12


def _load_tanh_table() -> np.ndarray:
    """sg_tanh_tab, read from sg_math.c itself so that C and twin cannot drift apart."""
    text = (CSRC / "sg_math.c").read_text()
    body = text[text.index("BEGIN sg_tanh_tab"):text.index("END sg_tanh_tab")]
    rows = re.findall(r"\{([^}]*)\}", body)
    tab = np.array([[float.fromhex(v.strip().rstrip("f")) for v in r.split(",")] for r in rows])
    assert tab.shape == (121, 6), tab.shape
    out = tab.astype(F32)
    assert np.array_equal(out.astype(np.float64), tab), "table entries must be float32 values"
    return out


_TANH_TAB = _load_tanh_table()
TANH_TABLE = _TANH_TAB   # sg_tanh_tab as laid out in flash (the integrity CRC covers it)


# The signed tanh table (network.c's <name>_tanh_rows, tanh.c's torque tanh): sg_tanh_tab with the
# sign of the argument folded in, for sg_tanhf's bits without |x| and without a final negation.
# Each half has TANH_HALF rows of TANH_COLS floats (a power of two: a row's address is one shift
# and add): sg_tanh_tab's 121 intervals, then rows that
# give exactly 1 for 9 <= |x| < 16 (c0 = 1, the rest 0), so that one compare of the two indices of a
# pair, OR-ed, tells whether both are in the table. For x < 0 the row of interval i is mirrored
# below the middle (row TANH_HALF - 1 - i) with the signs below: t = x + c = -(|x| - c) and a Horner
# chain whose every intermediate is sg_tanhf's or its exact negation, so -sg_tanhf(|x|) bit for bit.
TANH_HALF = 128
TANH_COLS = 8
TANH_MIRROR_SIGNS = np.array([-1, -1, 1, -1, 1, -1], dtype=np.float32)


def tanh_rows() -> np.ndarray:
    """The signed tanh table, (2 * TANH_HALF, TANH_COLS) float32: for x < 0 the mirrored rows (interval
    TANH_HALF - 1 first), then for x >= 0 sg_tanh_tab's rows, padded with zero columns."""
    tab = TANH_TABLE
    pos = np.zeros((TANH_HALF, TANH_COLS), dtype=np.float32)
    pos[:tab.shape[0], :6] = tab
    pos[tab.shape[0]:, 1] = 1.0  # tanh is 1 to float32 precision from 9 on (sg_tanhf's rule)
    neg = pos.copy()
    neg[:, :6] *= TANH_MIRROR_SIGNS
    return np.concatenate([neg[::-1], pos]).astype(np.float32)


_TANH_COLS = tuple(np.ascontiguousarray(_TANH_TAB[:, j]) for j in range(6))  # fast 1-D take


CANONICAL_NAN_BITS = 0x7FC00000


def canonf(x) -> np.ndarray:
    """sg_canonf: x, or the canonical quiet NaN (bits 0x7FC00000) where x is a NaN."""
    x = _f32(x)
    return np.where(np.isnan(x), np.uint32(CANONICAL_NAN_BITS).view(np.float32), x)


def tanhf(x) -> np.ndarray:
    """Mirror of sg_tanhf (and of sg_inline_tanhf, its inlined form): interval table indexed by
    exponent + 3 mantissa bits, degree-4 polynomial in |x| - c; x itself below 2^-12 and for
    NaN, +-1 (built from the sign bit) from 9 on."""
    x = _f32(x)
    with np.errstate(all="ignore"):
        ux = _as_u32(x)
        i = ((ux << U32(1)) >> U32(24 - _TANH_M)) - U32(_TANH_FIRST)
        inside = i < U32(len(_TANH_TAB))
        idx = np.where(inside, i, U32(0)).astype(np.intp)
        t = np.abs(x) - _TANH_COLS[0].take(idx)
        p = _TANH_COLS[5].take(idx)
        for j in (4, 3, 2, 1):
            p = p * t + _TANH_COLS[j].take(idx)
        neg = (ux >> U32(31)) != U32(0)
        y = np.where(neg, -p, p)
        sat = _as_f32((ux & U32(0x80000000)) | U32(0x3F800000))  # +-1 from the sign bit
        tiny = (ux << U32(1)) < U32((_TANH_TINY_BITS << 1) & 0xFFFFFFFF)
        out = np.where(tiny | np.isnan(x), x, sat)
        y = np.where(inside, y, out)
    return _check(y)


# ---------------------------------------------------------------- exp

_MAGIC = F32(float.fromhex("0x1.8p+23"))
_INV_LN2 = F32(float.fromhex("0x1.715476p+0"))
_LN2_HI = F32(float.fromhex("0x1.62e4p-1"))
_LN2_LO = F32(float.fromhex("0x1.7f7d1cp-20"))
EXP_OVF = F32(float.fromhex("0x1.62e42ep+6"))
EXP_UNF = F32(float.fromhex("-0x1.9fe368p+6"))
_EXP_P = tuple(float.fromhex(h) for h in ("0x1.6c5a98p-10", "0x1.12243ap-7", "0x1.5555b6p-5",
                                           "0x1.5554b6p-3", "0x1p-1", "0x1p+0"))
_INF = F32(np.inf)
_NAN = F32(np.nan)


def _pow2(u: np.ndarray, bias: int) -> np.ndarray:
    """sg_pow2: 2^(k + bias) from the bits u of k + MAGIC (uint32 wrap-around as in C)."""
    return _as_f32((u + U32(bias & 0xFFFFFFFF) + U32(127)) << U32(23))


def expf(x) -> np.ndarray:
    """Mirror of sg_expf: Cody-Waite ln2 reduction, degree-6 polynomial, s + s*q scaling."""
    x = _f32(x)
    with np.errstate(all="ignore"):
        inside = (x <= EXP_OVF) & (x >= EXP_UNF)
        xi = np.where(inside, x, F32(0.0))
        t = xi * _INV_LN2 + _MAGIC
        kf = t - _MAGIC
        r = (xi - kf * _LN2_HI) - kf * _LN2_LO
        q = _horner(r, _EXP_P) * r
        u = _as_u32(t)
        s0, s1, s2 = _pow2(u, 0), _pow2(u, -1), _pow2(u, 64)
        y = np.where((kf >= F32(-126.0)) & (kf <= F32(127.0)), s0 + s0 * q,
                     np.where(kf > F32(0.0), (s1 + s1 * q) * F32(2.0),
                              (s2 + s2 * q) * F32(2.0**-64)))
        special = np.where(np.isnan(x), x + x, np.where(x > F32(0.0), _INF, F32(0.0)))
        y = np.where(inside, y, special)
    return _check(y)


# ---------------------------------------------------------------- log

_LOG_R = tuple(float.fromhex(h) for h in ("0x1.2f29fep-2", "0x1.997aa8p-2", "0x1.55555cp-1"))


def logf(x) -> np.ndarray:
    """Mirror of sg_logf: m in [sqrt(1/2), sqrt 2), s = f/(2+f), fdlibm's summation order."""
    x = _f32(x)
    with np.errstate(all="ignore"):
        ix = _as_u32(x)
        rare = (ix < U32(0x00800000)) | (ix >= U32(0x7F800000))
        zero = (ix << U32(1)) == U32(0)
        sub = (ix < U32(0x00800000)) & ~zero
        ix = np.where(sub, _as_u32(x * F32(2.0**23)), ix)
        kbias = np.where(sub, F32(-23.0), F32(0.0))
        ix = ix + U32(0x3F800000 - 0x3F3504F3)
        kf = ((ix >> U32(23)).astype(np.int32) - np.int32(127)).astype(F32) + kbias
        f = _as_f32((ix & U32(0x007FFFFF)) + U32(0x3F3504F3)) - F32(1.0)
        s = f / (F32(2.0) + f)
        z = s * s
        rz = _horner(z, _LOG_R) * z
        hfsq = F32(0.5) * f * f
        y = (((s * (hfsq + rz) + kf * _LN2_LO) - hfsq) + f) + kf * _LN2_HI
        special = np.where(zero, -_INF,
                           np.where(np.isnan(x) | (x == _INF), x + x,
                                    np.where(x < F32(0.0), _NAN, y)))
        y = np.where(rare, special, y)
    return _check(y)


# ---------------------------------------------------------------- sin, cos

_TWO_OVER_PI = F32(float.fromhex("0x1.45f306p-1"))
_PIO2_PARTS = tuple(F32(float.fromhex(h)) for h in
                    ("0x1.92p+0", "0x1.fb4p-12", "0x1.444p-24", "0x1.68c234p-39"))
_PIO4 = F32(float.fromhex("0x1.921fb6p-1"))
_SIN_P = tuple(float.fromhex(h) for h in ("-0x1.9952ecp-13", "0x1.110776p-7", "-0x1.555546p-3"))
_COS_P = tuple(float.fromhex(h) for h in ("0x1.9b8a82p-16", "-0x1.6c123cp-10", "0x1.555554p-5"))


def _trig_reduce(x: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The reduction part of sg_trig: (rhi, rlo, j mod 4)."""
    p1, p2, p3, p4 = _PIO2_PARTS
    t = x * _TWO_OVER_PI + _MAGIC
    jf = t - _MAGIC
    t2 = (x - jf * p1) - jf * p2
    w = jf * p3
    hi = t2 - w
    lo = ((t2 - hi) - w) - jf * p4
    outside = ~(np.abs(x) <= TRIG_MAX_ARG)
    clamped = np.where(hi > _PIO4, _PIO4, np.where(hi < -_PIO4, -_PIO4, hi))
    hi = np.where(outside, clamped, hi)
    lo = np.where(outside, F32(0.0), lo)
    return hi, lo, _as_u32(t) & U32(3)


def _sin_kernel(hi: np.ndarray, lo: np.ndarray) -> np.ndarray:
    z = hi * hi
    return hi + (hi * (z * _horner(z, _SIN_P)) + lo)


def _cos_kernel(hi: np.ndarray, lo: np.ndarray) -> np.ndarray:
    z = hi * hi
    return F32(1.0) - (F32(0.5) * z - (z * (z * _horner(z, _COS_P)) - hi * lo))


def _trig_quadrant(n: np.ndarray, hi: np.ndarray, lo: np.ndarray) -> np.ndarray:
    y = np.where((n & U32(1)) != 0, _cos_kernel(hi, lo), _sin_kernel(hi, lo))
    return np.where((n & U32(2)) != 0, -y, y)


def sinf(x) -> np.ndarray:
    """Mirror of sg_sinf = sg_trig(x, 0) (x itself below 2^-12, which covers -0 and NaN)."""
    x = _f32(x)
    with np.errstate(all="ignore"):
        hi, lo, n = _trig_reduce(x)
        y = np.where(~(np.abs(x) >= F32(2.0**-12)), x, _trig_quadrant(n, hi, lo))
    return _check(y)


def cosf(x) -> np.ndarray:
    """Mirror of sg_cosf = sg_trig(x, 1): the quadrant shifted by one."""
    x = _f32(x)
    with np.errstate(all="ignore"):
        hi, lo, n = _trig_reduce(x)
        y = _trig_quadrant(n + U32(1), hi, lo)
    return _check(y)


# ---------------------------------------------------------------- asin, atan2

PIO2_HI = F32(float.fromhex("0x1.921fb6p+0"))
_PIO2_LO = F32(float.fromhex("-0x1.777a5cp-25"))
PI_HI = F32(float.fromhex("0x1.921fb6p+1"))
_PI_LO = F32(float.fromhex("-0x1.777a5cp-24"))
_PI3O4 = F32(float.fromhex("0x1.2d97c8p+1"))
_ASIN_P = tuple(float.fromhex(h) for h in
                ("0x1.596d5cp-5", "0x1.8c2d86p-6", "0x1.747d06p-5", "0x1.3301fcp-4",
                 "0x1.5555c8p-3"))
_ATAN_P = tuple(float.fromhex(h) for h in
                ("-0x1.d32dacp-10", "0x1.6410e4p-7", "-0x1.fd6fbcp-6", "0x1.da24cap-5",
                 "-0x1.580814p-4", "0x1.c08c1ap-4", "-0x1.242084p-3", "0x1.9991e4p-3",
                 "-0x1.55553ep-2"))


def _asin_tail(x: np.ndarray, z: np.ndarray) -> np.ndarray:
    return x * (z * _horner(z, _ASIN_P))


def asinf(x) -> np.ndarray:
    """Mirror of sg_asinf: odd polynomial below 1/2, pi/2 - 2 asin(sqrt((1-|x|)/2)) above."""
    x = _f32(x)
    with np.errstate(all="ignore"):
        a = np.abs(x)
        small = np.where(a < F32(2.0**-12), x, x + _asin_tail(x, x * x))
        z = (F32(1.0) - a) * F32(0.5)
        s = np.sqrt(z)
        u = F32(2.0) * _asin_tail(s, z) - _PIO2_LO
        big = np.where(s >= F32(0.3125), (PIO2_HI - F32(2.0) * s) - u,
                       PIO2_HI - (F32(2.0) * s + u))
        big = np.where(x < F32(0.0), -big, big)
        y = np.where(a < F32(0.5), small, big)
        y = np.where(a <= F32(1.0), y, np.where(np.isnan(x), x + x, _NAN))
    return _check(y)


def _atan_kernel(q: np.ndarray) -> np.ndarray:
    z = q * q
    return q + q * (z * _horner(z, _ATAN_P))


def _atan2_special(y, x, a, b, xneg) -> np.ndarray:
    t = np.where(a == _INF, np.where(b == _INF, np.where(xneg, _PI3O4, _PIO4), PIO2_HI),
                 np.where((b == _INF) | (a == F32(0.0)), np.where(xneg, PI_HI, F32(0.0)),
                          PIO2_HI))
    t = np.where((_as_u32(y) >> U32(31)) != 0, -t, t)
    return np.where(np.isnan(x) | np.isnan(y), x + y, t)


def atan2f(y, x) -> np.ndarray:
    """Mirror of sg_atan2f(y, x): atan of min/max, quadrant fix-ups, Annex F special cases."""
    y, x = np.broadcast_arrays(_f32(y), _f32(x))
    with np.errstate(all="ignore"):
        a, b = np.abs(y), np.abs(x)
        xneg = (_as_u32(x) >> U32(31)) != 0
        fast = (a > F32(0.0)) & (a < _INF) & (b > F32(0.0)) & (b < _INF)
        swap = a > b
        k = _atan_kernel(np.where(swap, b, a) / np.where(swap, a, b))
        t = np.where(swap, PIO2_HI + (_PIO2_LO - k), k)
        t = np.where(xneg, PI_HI + (_PI_LO - t), t)
        t = np.where((_as_u32(y) >> U32(31)) != 0, -t, t)
        r = np.where(fast, t, _atan2_special(y, x, a, b, xneg))
    return _check(r)


# ---------------------------------------------------------------- sqrt, pow

def sqrtf(x) -> np.ndarray:
    """Mirror of sg_sqrtf: IEEE sqrt is correctly rounded everywhere (VSQRT, sqrtss, numpy)."""
    with np.errstate(all="ignore"):
        return _check(np.sqrt(_f32(x)))


def powf_pos(x, y) -> np.ndarray:
    """Mirror of sg_powf_pos: 1 if y == 0 or x == 1, NaN if x < 0, else expf(y * logf(x))."""
    x, y = np.broadcast_arrays(_f32(x), _f32(y))
    with np.errstate(all="ignore"):
        r = expf(y * logf(x))
        r = np.where((y == F32(0.0)) | (x == F32(1.0)), F32(1.0),
                     np.where(x < F32(0.0), _NAN, r))
    return _check(r)


# ---------------------------------------------------------------- fused power (sg_powf_fused)

_PF_LOG2 = tuple(float.fromhex(h) for h in (
    "-0x1.2a5f1ap-3", "0x1.e50a6ap-3", "-0x1.0011d6p-2", "0x1.25992ap-2",
    "-0x1.70baf6p-2", "0x1.ec7b3ep-2", "-0x1.7155b8p-1", "0x1.715472p+0"))  # c7 .. c0
_PF_EXP2 = tuple(float.fromhex(h) for h in (
    "0x1.417a9cp-13", "0x1.5f0948p-10", "0x1.3b2dd2p-7", "0x1.c6af7ap-5",
    "0x1.ebfbdcp-3", "0x1.62e43p-1"))  # e5 .. e0
#: |y log2 x| below which sg_powf_fused takes its fast path (the result is then normal).
POWF_FUSED_MAX_T = F32(125.0)
#: Published bound of sg_powf_fused on its fast path (measured in docs/math.md, asserted by tests):
#: error <= POWF_FUSED_ULP_BASE + POWF_FUSED_ULP_PER_Y * |y| ulp (the log2 polynomial's error is
#: scaled by y; it does not grow with |y log2 x| as powf_pos's does).
POWF_FUSED_ULP_BASE = 1.2
POWF_FUSED_ULP_PER_Y = 1.0


def powf_fused(x, y) -> np.ndarray:
    """Mirror of sg_powf_fused (sg_math.h): x^y = 2^(y log2 x) in one pass for x positive normal
    and |y log2 x| < 125; otherwise powf_pos(x, y)."""
    x, y = np.broadcast_arrays(_f32(x), _f32(y))
    with np.errstate(all="ignore"):
        bx = _as_u32(x)
        fast = (bx - U32(0x00800000)) < U32(0x7F000000)
        ix = bx + U32(0x3F800000 - 0x3F3504F3)
        kf = ((ix >> U32(23)).astype(np.int32) - np.int32(127)).astype(F32)
        f = _as_f32((ix & U32(0x007FFFFF)) + U32(0x3F3504F3)) - F32(1.0)
        lm = f * _horner(f, _PF_LOG2)
        yh = _as_f32(_as_u32(y) & U32(0xFFFFF000))
        yl = y - yh
        th = yh * kf
        tl = yl * kf + y * lm
        t = th + tl
        fast = fast & (np.abs(t) < POWF_FUSED_MAX_T)
        bt = t + _MAGIC
        nf = bt - _MAGIC
        r = (th - nf) + tl
        p = F32(1.0) + r * _horner(r, _PF_EXP2)
        res = _as_f32(_as_u32(p) + (_as_u32(bt) << U32(23)))
        out = np.where(fast, res, powf_pos(x, y))
    return _check(out)


# ---------------------------------------------------------------- powf_tab (sg_math.h)

_PT_LOG = np.array([
    (float.fromhex("0x1.6ap-1"), float.fromhex("0x1.6a13cep+0"), float.fromhex("-0x1.001434p-1")),
    (float.fromhex("0x1.72p-1"), float.fromhex("0x1.623fa8p+0"), float.fromhex("-0x1.dfdd8ap-2")),
    (float.fromhex("0x1.7ap-1"), float.fromhex("0x1.5ac056p+0"), float.fromhex("-0x1.c04386p-2")),
    (float.fromhex("0x1.82p-1"), float.fromhex("0x1.539094p+0"), float.fromhex("-0x1.a152f2p-2")),
    (float.fromhex("0x1.8ap-1"), float.fromhex("0x1.4cab88p+0"), float.fromhex("-0x1.8304dap-2")),
    (float.fromhex("0x1.92p-1"), float.fromhex("0x1.460cbcp+0"), float.fromhex("-0x1.6552b4p-2")),
    (float.fromhex("0x1.9ap-1"), float.fromhex("0x1.3fb014p+0"), float.fromhex("-0x1.48365ep-2")),
    (float.fromhex("0x1.a2p-1"), float.fromhex("0x1.3991c2p+0"), float.fromhex("-0x1.2baa0cp-2")),
    (float.fromhex("0x1.aap-1"), float.fromhex("0x1.33ae46p+0"), float.fromhex("-0x1.0fa848p-2")),
    (float.fromhex("0x1.b2p-1"), float.fromhex("0x1.2e025cp+0"), float.fromhex("-0x1.e857d4p-3")),
    (float.fromhex("0x1.bap-1"), float.fromhex("0x1.288b02p+0"), float.fromhex("-0x1.b26024p-3")),
    (float.fromhex("0x1.c2p-1"), float.fromhex("0x1.234568p+0"), float.fromhex("-0x1.7d604ap-3")),
    (float.fromhex("0x1.cap-1"), float.fromhex("0x1.1e2ef4p+0"), float.fromhex("-0x1.494f86p-3")),
    (float.fromhex("0x1.d2p-1"), float.fromhex("0x1.194538p+0"), float.fromhex("-0x1.162594p-3")),
    (float.fromhex("0x1.dap-1"), float.fromhex("0x1.1485fp+0"), float.fromhex("-0x1.c7b528p-4")),
    (float.fromhex("0x1.e2p-1"), float.fromhex("0x1.0fef02p+0"), float.fromhex("-0x1.64ce26p-4")),
    (float.fromhex("0x1.eap-1"), float.fromhex("0x1.0b7e6ep+0"), float.fromhex("-0x1.0387fp-4")),
    (float.fromhex("0x1.f2p-1"), float.fromhex("0x1.07326p+0"), float.fromhex("-0x1.47aa08p-5")),
    (float.fromhex("0x1.fap-1"), float.fromhex("0x1.03091cp+0"), float.fromhex("-0x1.16a21ep-6")),
    (float.fromhex("0x1.028p+0"), float.fromhex("0x1.fb0c62p-1"), float.fromhex("0x1.cb6c3ap-7")),
    (float.fromhex("0x1.0ap+0"), float.fromhex("0x1.ecc07cp-1"), float.fromhex("0x1.c4dfacp-5")),
    (float.fromhex("0x1.12p+0"), float.fromhex("0x1.de5d6ep-1"), float.fromhex("0x1.918a16p-4")),
    (float.fromhex("0x1.1ap+0"), float.fromhex("0x1.d0cb58p-1"), float.fromhex("0x1.1dcd1ap-3")),
    (float.fromhex("0x1.22p+0"), float.fromhex("0x1.c3f8fp-1"), float.fromhex("0x1.70742ep-3")),
    (float.fromhex("0x1.2ap+0"), float.fromhex("0x1.b7d6c4p-1"), float.fromhex("0x1.c0db6cp-3")),
    (float.fromhex("0x1.32p+0"), float.fromhex("0x1.ac5702p-1"), float.fromhex("0x1.0790aep-2")),
    (float.fromhex("0x1.3ap+0"), float.fromhex("0x1.a16d4p-1"), float.fromhex("0x1.2db11p-2")),
    (float.fromhex("0x1.42p+0"), float.fromhex("0x1.970e5p-1"), float.fromhex("0x1.52dbep-2")),
    (float.fromhex("0x1.4ap+0"), float.fromhex("0x1.8d3018p-1"), float.fromhex("0x1.771d2cp-2")),
    (float.fromhex("0x1.52p+0"), float.fromhex("0x1.83c978p-1"), float.fromhex("0x1.9a8024p-2")),
    (float.fromhex("0x1.5ap+0"), float.fromhex("0x1.7ad22p-1"), float.fromhex("0x1.bd0f2ep-2")),
    (float.fromhex("0x1.62p+0"), float.fromhex("0x1.724288p-1"), float.fromhex("0x1.ded3fep-2")),
], dtype=F32)
_PT_A = tuple(F32(v) for v in (float.fromhex("0x1.715476p+0"), float.fromhex("-0x1.715daep-1"), float.fromhex("0x1.ec89cap-2")))  # a0, a1, a2
_PT_B = tuple(F32(v) for v in (float.fromhex("0x1.62e43p-6"), float.fromhex("0x1.ebfce6p-13"), float.fromhex("0x1.c6b186p-20")))  # b0, b1, b2
_PT_EXP2 = np.array([0x3f800000, 0x3f82cd87, 0x3f85aac3, 0x3f88980f, 0x3f8b95c2, 0x3f8ea43a, 0x3f91c3d3, 0x3f94f4f0, 0x3f9837f0, 0x3f9b8d3a, 0x3f9ef532, 0x3fa27043, 0x3fa5fed7, 0x3fa9a15b, 0x3fad583f, 0x3fb123f6, 0x3fb504f3, 0x3fb8fbaf, 0x3fbd08a4, 0x3fc12c4d, 0x3fc5672a, 0x3fc9b9be, 0x3fce248c, 0x3fd2a81e, 0x3fd744fd, 0x3fdbfbb8, 0x3fe0ccdf, 0x3fe5b907, 0x3feac0c7, 0x3fefe4ba, 0x3ff5257d, 0x3ffa83b3], dtype=np.uint32)
#: powf_tab fast path: error <= POWF_TAB_ULP_BASE + POWF_TAB_ULP_PER_Y * |y| ulp (sampled,
#: tests/test_detmath.py; docs/math.md).
POWF_TAB_ULP_BASE = 1.2
POWF_TAB_ULP_PER_Y = 1.0


def powf_tab(x, y) -> np.ndarray:
    """Mirror of sg_powf_tab (sg_math.h): table-driven 2^(y log2 x) for x positive normal and
    |y log2 x| < 125; otherwise powf_pos(x, y)."""
    x, y = np.broadcast_arrays(_f32(x), _f32(y))
    with np.errstate(all="ignore"):
        bx = _as_u32(x)
        fast = (bx - U32(0x00800000)) < U32(0x7F000000)
        ix = bx + U32(0x3F800000 - 0x3F330000)
        kf = ((ix >> U32(23)).astype(np.int32) - np.int32(127)).astype(F32)
        row = _PT_LOG[((ix >> U32(18)) & U32(31)).astype(np.intp)]
        z = _as_f32((ix & U32(0x007FFFFF)) + U32(0x3F330000))
        a0, a1, a2 = _PT_A
        r = (z - row[..., 0]) * row[..., 1]
        lz = row[..., 2] + r * ((a2 * r + a1) * r + a0)
        y32 = F32(32.0) * y
        yh = _as_f32(_as_u32(y32) & U32(0xFFFFF000))
        yl = y32 - yh
        th = yh * kf
        tl = yl * kf + y32 * lz
        t = th + tl
        fast = fast & ((np.abs(y) <= F32(float.fromhex("0x1.fp-1"))) | (np.abs(t) < F32(32.0) * POWF_FUSED_MAX_T))
        bt = t + _MAGIC
        nf = bt - _MAGIC
        u = (th - nf) + tl
        b0, b1, b2 = _PT_B
        q = u * ((b2 * u + b1) * u + b0)
        s = _as_f32(_PT_EXP2[(_as_u32(bt) & U32(31)).astype(np.intp)] + ((_as_u32(bt) >> U32(5)) << U32(23)))
        res = s + s * q
        out = np.where(fast, res, powf_pos(x, y))
    return _check(out)


# ---------------------------------------------------------------- powf_const (sg_math.h)

#: powf_const: error <= POWC_ULP ulp for x positive normal. Exhaustive over all positive normal x
#: (independent 60-digit Decimal reference): 2.545 ulp for y = float32(0.8) at x = 0x1.6a09dp+87,
#: 2.348 for y = float32(-0.2); sampled elsewhere (tests/test_detmath.py, docs/math.md).
POWC_ULP = 2.6
SG_POWC_NK = 255


class PowC(NamedTuple):
    """The tables of sg_powc_t for one exponent y (float32 arrays, the C struct's fields)."""
    y: np.float32
    p: tuple  # p0 .. p3, float32
    cy: np.ndarray  # (32,) c_i^y
    ek: np.ndarray  # (255,) 2^(y k), k = -126 .. 128


def decimal_pow(base: float, exponent: float, scale: float = 1.0) -> decimal.Decimal:
    """scale * base**exponent for base > 0 from the exact binary values, to 40 significant digits
    (byte-identical table entries on every host)."""
    with decimal.localcontext() as ctx:
        ctx.prec = 40
        return decimal.Decimal(scale) * (decimal.Decimal(exponent) * decimal.Decimal(base).ln()).exp()


@functools.lru_cache(maxsize=64)
def _powc_tables(ybits: int) -> PowC:
    y32 = np.uint32(ybits).view(F32)
    y = float(y32)
    if not (math.isfinite(y) and abs(y) < 1.0):
        raise ValueError(f"powc_tables: |y| must be < 1, got {y!r}")
    p = (y, y * (y - 1.0) / 2.0, y * (y - 1.0) * (y - 2.0) / 6.0, y * (y - 1.0) * (y - 2.0) * (y - 3.0) / 24.0)
    # Decimal, not float `**`: the host's libm pow may differ between machines, and the generated
    # sources must be byte-identical everywhere (exact y, 40 digits, then rounded).
    cy = np.array([float(decimal_pow(float(c), y)) for c in _PT_LOG[:, 0]], dtype=F32)
    # |y| <= 31/32 keeps every entry (and result) normal; closer to 1 the ends are clamped to the
    # float32 range (deterministic, outside the asserted error bound)
    ek = np.array([min(float(decimal_pow(2.0, y * k)), float(np.finfo(F32).max)) for k in range(-126, 129)],
                  dtype=F32)
    return PowC(y32, tuple(F32(v) for v in p), cy, ek)


def powc_tables(y) -> PowC:
    """sg_powc_t for the float32 exponent y (|y| < 1; error bound asserted for |y| <= 31/32): p from Taylor coefficients, c_i^y and
    2^(y k) in float64 rounded once to float32. Emitted by the code generator, used by the twin."""
    return _powc_tables(int(F32(y).view(np.uint32)))


def powc_c_initializer(t: PowC, indent: str = "    ") -> str:
    """The C initializer of an sg_powc_t (hex-float literals): y, p, the 32 interval rows {c_i, 1/c_i,
    c_i^y, 0} (c_i, 1/c_i those of sg_powf_tab_log) and 2^(y k), 8 per line."""
    def rows(a):
        return (",\n" + indent * 2).join(", ".join(c_float(v) for v in a[i:i + 8]) for i in range(0, len(a), 8))
    interval_rows = (",\n" + indent * 2).join(
        "{" + ", ".join(c_float(v) for v in (F32(c), F32(ic), cy, F32(0.0))) + "}"
        for (c, ic, _log2c), cy in zip(_PT_LOG, t.cy))
    return ("{\n" + indent + c_float(t.y) + ",\n" + indent + "{" + ", ".join(c_float(v) for v in t.p) + "},\n"
            + indent + "{\n" + indent * 2 + interval_rows + "\n" + indent + "},\n"
            + indent + "{\n" + indent * 2 + rows(t.ek) + "\n" + indent + "}\n}")


def powf_const(x, t: PowC) -> np.ndarray:
    """Mirror of sg_powf_const (sg_math.h): x^y from the tables t = powc_tables(y) for x positive
    normal; +0 for x = +0 or subnormal when y > 0; otherwise powf_pos(x, y)."""
    x = _f32(x)
    with np.errstate(all="ignore"):
        bx = _as_u32(x)
        fast = (bx - U32(0x00800000)) < U32(0x7F000000)
        ix = bx + U32(0x3F800000 - 0x3F330000)
        i = ((ix >> U32(18)) & U32(31)).astype(np.intp)
        row = _PT_LOG[i]
        z = _as_f32((ix & U32(0x007FFFFF)) + U32(0x3F330000))
        kk = np.clip((ix >> U32(23)).astype(np.intp) - 1, 0, SG_POWC_NK - 1)
        p0, p1, p2, p3 = t.p
        r = (z - row[..., 0]) * row[..., 1]
        q = r * (((p3 * r + p2) * r + p1) * r + p0)
        s = t.cy[i] * t.ek[kk]
        res = s + s * q
        flush = (bx < U32(0x00800000)) & (t.y > F32(0.0))  # +0 and subnormal x, y > 0: +0
        out = np.where(fast, res, np.where(flush, F32(0.0), powf_pos(x, t.y)))
    return _check(np.asarray(out, dtype=F32))


# ---------------------------------------------------------------- logf_tab (sg_math.h)

_LT_ROWS = np.array([
    (float.fromhex("0x1.6ap-1"), float.fromhex("0x1.6a13cep+0"), float.fromhex("-0x1.63003p-2")),
    (float.fromhex("0x1.72p-1"), float.fromhex("0x1.623fa8p+0"), float.fromhex("-0x1.4c9e0ap-2")),
    (float.fromhex("0x1.7ap-1"), float.fromhex("0x1.5ac056p+0"), float.fromhex("-0x1.36b678p-2")),
    (float.fromhex("0x1.82p-1"), float.fromhex("0x1.539094p+0"), float.fromhex("-0x1.214456p-2")),
    (float.fromhex("0x1.8ap-1"), float.fromhex("0x1.4cab88p+0"), float.fromhex("-0x1.0c42d6p-2")),
    (float.fromhex("0x1.92p-1"), float.fromhex("0x1.460cbcp+0"), float.fromhex("-0x1.ef5adep-3")),
    (float.fromhex("0x1.9ap-1"), float.fromhex("0x1.3fb014p+0"), float.fromhex("-0x1.c6ffbcp-3")),
    (float.fromhex("0x1.a2p-1"), float.fromhex("0x1.3991c2p+0"), float.fromhex("-0x1.9f6c4p-3")),
    (float.fromhex("0x1.aap-1"), float.fromhex("0x1.33ae46p+0"), float.fromhex("-0x1.7898d8p-3")),
    (float.fromhex("0x1.b2p-1"), float.fromhex("0x1.2e025cp+0"), float.fromhex("-0x1.527e5ep-3")),
    (float.fromhex("0x1.bap-1"), float.fromhex("0x1.288b02p+0"), float.fromhex("-0x1.2d161p-3")),
    (float.fromhex("0x1.c2p-1"), float.fromhex("0x1.234568p+0"), float.fromhex("-0x1.08598cp-3")),
    (float.fromhex("0x1.cap-1"), float.fromhex("0x1.1e2ef4p+0"), float.fromhex("-0x1.c8858p-4")),
    (float.fromhex("0x1.d2p-1"), float.fromhex("0x1.194538p+0"), float.fromhex("-0x1.8197e2p-4")),
    (float.fromhex("0x1.dap-1"), float.fromhex("0x1.1485fp+0"), float.fromhex("-0x1.3bdf5ap-4")),
    (float.fromhex("0x1.e2p-1"), float.fromhex("0x1.0fef02p+0"), float.fromhex("-0x1.eea31cp-5")),
    (float.fromhex("0x1.eap-1"), float.fromhex("0x1.0b7e6ep+0"), float.fromhex("-0x1.67c95p-5")),
    (float.fromhex("0x1.f2p-1"), float.fromhex("0x1.07326p+0"), float.fromhex("-0x1.c63d2ep-6")),
    (float.fromhex("0x1.fap-1"), float.fromhex("0x1.03091cp+0"), float.fromhex("-0x1.82448ap-7")),
    (float.fromhex("0x1.0p+0"), float.fromhex("0x1.0p+0"), 0.0),
    (float.fromhex("0x1.0ap+0"), float.fromhex("0x1.ecc07cp-1"), float.fromhex("0x1.39e87cp-5")),
    (float.fromhex("0x1.12p+0"), float.fromhex("0x1.de5d6ep-1"), float.fromhex("0x1.16536ep-4")),
    (float.fromhex("0x1.1ap+0"), float.fromhex("0x1.d0cb58p-1"), float.fromhex("0x1.8c345ep-4")),
    (float.fromhex("0x1.22p+0"), float.fromhex("0x1.c3f8fp-1"), float.fromhex("0x1.fec914p-4")),
    (float.fromhex("0x1.2ap+0"), float.fromhex("0x1.b7d6c4p-1"), float.fromhex("0x1.371fc2p-3")),
    (float.fromhex("0x1.32p+0"), float.fromhex("0x1.ac5702p-1"), float.fromhex("0x1.6d60fep-3")),
    (float.fromhex("0x1.3ap+0"), float.fromhex("0x1.a16d4p-1"), float.fromhex("0x1.a23bc2p-3")),
    (float.fromhex("0x1.42p+0"), float.fromhex("0x1.970e5p-1"), float.fromhex("0x1.d5c216p-3")),
    (float.fromhex("0x1.4ap+0"), float.fromhex("0x1.8d3018p-1"), float.fromhex("0x1.04025ap-2")),
    (float.fromhex("0x1.52p+0"), float.fromhex("0x1.83c978p-1"), float.fromhex("0x1.1c898cp-2")),
    (float.fromhex("0x1.5ap+0"), float.fromhex("0x1.7ad22p-1"), float.fromhex("0x1.347ddap-2")),
    (float.fromhex("0x1.62p+0"), float.fromhex("0x1.724288p-1"), float.fromhex("0x1.4be5fap-2")),
], dtype=F32)
#: logf_tab: error <= LOGF_TAB_ULP ulp for x positive normal (sampled, tests/test_detmath.py).
LOGF_TAB_ULP = 3.0


# sg_logf_tab's polynomial coefficients of r^4 and r^2 (sg_math.h), also in the tanh law's log table.
LOGF_TAB_C4 = F32(float.fromhex("0x1.99999ap-3"))
LOGF_TAB_C2 = F32(float.fromhex("0x1.555556p-2"))
LN2_HI, LN2_LO = _LN2_HI, _LN2_LO   # ln 2 split as sg_logf_tab and sg_expf use it


def logf_tab(x) -> np.ndarray:
    """Mirror of sg_logf_tab (sg_math.h): table-driven ln x for x positive normal; else logf(x)."""
    x = _f32(x)
    with np.errstate(all="ignore"):
        bx = _as_u32(x)
        fast = (bx - U32(0x00800000)) < U32(0x7F000000)
        ix = bx + U32(0x3F800000 - 0x3F330000)
        kf = ((ix >> U32(23)).astype(np.int32) - np.int32(127)).astype(F32)
        row = _LT_ROWS[((ix >> U32(18)) & U32(31)).astype(np.intp)]
        z = _as_f32((ix & U32(0x007FFFFF)) + U32(0x3F330000))
        r = (z - row[..., 0]) * row[..., 1]
        p = (((LOGF_TAB_C4 * r - F32(0.25)) * r + LOGF_TAB_C2) * r - F32(0.5)) * r
        lz = row[..., 2] + r * (p + F32(1.0))
        res = kf * LN2_HI + (kf * LN2_LO + lz)
        out = np.where(fast, res, logf(x))
    return _check(np.asarray(out, dtype=F32))
