"""The controller C's cheaper forms of the same arithmetic (docs/controller.md, "Cost"): each is
checked here against the form the golden model keeps, beyond what the three-way gate samples.

- the envelope and the saturation tested on bit patterns == the float comparisons;
- GMST in Horner form == A + B d + Q (2d - 1)^2 (mod 2^64) on every accepted day;
- sin/cos of a Q32-turn remainder by the kernels alone == sg_sinf / sg_cosf (detmath);
- an A_bd off the attitude's short paths is outside +-WIDE_ANGLE_DEG (or NaN), so the step's
  wide branch, which never calls the network, loses nothing.
"""
import math

import numpy as np

from codegen import detmath as dm
from codegen.units.controller import emit
from codegen.units.controller import golden as gc
from codegen.units.controller import spec as cs
from codegen.units.controller.emit import TURN32_HI, TURN32_LO, envelope_checks, envelope_outside
from host.control.nn_controller import flight_config, load_artifact

F32, U32 = np.float32, np.uint32


def _special_and_near(bounds) -> np.ndarray:
    """Float32 values around every bound (+-4 ulp), the special values and random bit patterns."""
    rng = np.random.default_rng(5)
    vals = [np.float32(v) for v in (0.0, -0.0, np.inf, -np.inf, np.nan, -np.nan, 1e-45, -1e-45,
                                    np.finfo(F32).max, -np.finfo(F32).max, 1.0, -1.0)]
    for b in np.asarray(bounds, dtype=F32).ravel():
        for d in range(-4, 5):
            bits = int(np.float32(b).view(U32))
            vals.append(np.uint32((bits + d) & 0xFFFFFFFF).view(F32))
            vals.append(np.float32(-b))
    out = np.array(vals, dtype=F32)
    return np.concatenate([out, rng.integers(0, 2**32, 20000, dtype=np.uint64).astype(U32).view(F32)])


def test_envelope_on_bit_patterns_equals_the_float_test():
    a = load_artifact(None)
    shapes = [(a.envelope.min, a.envelope.max),
              (np.array([-1.0, 0.0, -0.0, 0.5, -3.0, 2.0], F32), np.array([1.0, 2.0, 0.0, 0.25, -0.0, 2.0], F32)),
              (np.array([0.0, -0.0, -2.5], F32), np.array([0.0, 1e-30, -1e-3], F32))]
    for lo, hi in shapes:
        lo, hi = np.asarray(lo, F32), np.asarray(hi, F32)
        x = _special_and_near(np.concatenate([lo, hi]))
        xs = np.repeat(x[:, None], lo.size, axis=1)
        with np.errstate(invalid="ignore"):
            want = ~((xs >= lo) & (xs <= hi))
        got = envelope_outside(envelope_checks(lo, hi), xs.view(U32))
        assert np.array_equal(got, want)


def test_saturation_and_limits_on_bit_patterns_equal_the_float_tests():
    for limit in (1.0, 0.3, 100.0, 3.4e38):
        lim = np.float32(limit)
        x = _special_and_near([lim])
        b = x.view(U32).astype(np.uint64)
        with np.errstate(invalid="ignore"):
            outside = ~((x >= -lim) & (x <= lim))
            assert np.array_equal(((b << 1) & 0xFFFFFFFF) > ((int(lim.view(U32)) << 1) & 0xFFFFFFFF), outside)
            clipped = gc.clip(x, lim)
        nan = ((b << 1) & 0xFFFFFFFF) > 0xFF000000
        bits = np.where(nan, 0, (b & 0x80000000) | int(lim.view(U32))).astype(U32)
        assert np.array_equal(bits[outside], clipped[outside].view(U32))
    # non-finite as (b << 1) >= 0xFF000000
    x = _special_and_near([1.0])
    b = x.view(U32).astype(np.uint64)
    with np.errstate(invalid="ignore"):
        assert np.array_equal(((b << 1) & 0xFFFFFFFF) >= 0xFF000000, (x - x) != 0)


def test_gmst_horner_form_equals_the_spec_formula_on_every_day():
    h = emit.gmst_horner()
    a2, b2, q4 = int(h["gmst_a2"], 16), int(h["gmst_b2"], 16), int(h["gmst_q4"])
    day = np.arange(cs.UTC_DAY_MIN, cs.UTC_DAY_MAX + 1, dtype=np.int64)
    for ms in (0, 1, 43_200_000, cs.UTC_MS_MAX - 1):
        msa = np.full(day.shape, ms, dtype=np.int64)
        want = gc.gmst_turns(day, msa)
        with np.errstate(over="ignore"):   # mod 2^64, as the C
            inner = np.uint64(b2) + (q4 * day).astype(np.uint64)
            q = np.uint64(a2) + day.astype(np.uint64) * inner + np.uint64(ms) * np.uint64(cs.GMST_R)
        assert np.array_equal((q >> np.uint64(32)).astype(U32), want)
    assert q4 * max(-cs.UTC_DAY_MIN, cs.UTC_DAY_MAX) < 2**31


def _remainder(v: np.ndarray) -> np.ndarray:
    """The C's r of sincos_turns for v = turns + 2^29 (codegen.units.controller.golden.sincos_turns)."""
    hi = ((v & U32(0x3FFFFF00)).astype(np.int32) - np.int32(0x20000000)).astype(F32)
    lo = (v & U32(0xFF)).astype(np.int32).astype(F32)
    return hi * F32(TURN32_HI) + (hi * F32(TURN32_LO) + lo * F32(TURN32_HI))


def test_quadrant_remainder_needs_only_the_kernels():
    """sg_sinf(r), sg_cosf(r) == the kernels at hi = r, lo = 0 for every reachable remainder r:
    the extreme ones (the remainder's ends), those near 2^-12 and random ones."""
    rng = np.random.default_rng(9)
    ends = np.concatenate([np.arange(0, 1 << 16, dtype=np.uint64), np.arange((1 << 30) - (1 << 16), 1 << 30, dtype=np.uint64)])
    v = np.concatenate([ends, rng.integers(0, 1 << 30, 1 << 20, dtype=np.uint64),
                        (1 << 29) + np.arange(-(1 << 20), 1 << 20, dtype=np.int64).astype(np.uint64)]).astype(U32)
    r = _remainder(v)
    assert float(np.max(np.abs(r))) <= math.pi / 4 * (1 + 1e-6)
    z = r * r
    ps, pc = F32(float.fromhex("-0x1.9952ecp-13")), F32(float.fromhex("0x1.9b8a82p-16"))
    ps, pc = ps * z + F32(float.fromhex("0x1.110776p-7")), pc * z - F32(float.fromhex("0x1.6c123cp-10"))
    ps, pc = ps * z - F32(float.fromhex("0x1.555546p-3")), pc * z + F32(float.fromhex("0x1.555554p-5"))
    s = np.where(np.abs(r) >= F32(2.0**-12), r + r * (z * ps), r)
    c = F32(1.0) - (F32(0.5) * z - z * (z * pc))
    assert np.array_equal(s.view(U32), dm.sinf(r).view(U32))
    assert np.array_equal(c.view(U32), dm.cosf(r).view(U32))


def test_off_the_short_paths_the_angle_is_outside_the_envelope():
    """atan2_small / asin_small arguments that miss the short paths (the step's wide branch) give
    |angle| * 180/pi > WIDE_ANGLE_DEG or NaN; x = +0, y = +-0 is a short case (y itself)."""
    rng = np.random.default_rng(3)
    n = 400_000
    x = np.concatenate([rng.standard_normal(n).astype(F32), np.abs(rng.standard_normal(n)).astype(F32),
                        rng.integers(0, 2**32, n, dtype=np.uint64).astype(U32).view(F32)])
    y = np.concatenate([rng.standard_normal(n).astype(F32) * F32(1e-3), x[n:2 * n] * F32(2.0**-10)
                        * rng.uniform(0.99, 1.01, n).astype(F32),
                        rng.integers(0, 2**32, n, dtype=np.uint64).astype(U32).view(F32)])
    x = np.concatenate([x, np.array([0.0, 0.0, -0.0, -0.0, 1e-45, 1e-45, np.inf], F32)])
    y = np.concatenate([y, np.array([0.0, -0.0, 0.0, -0.0, 0.0, 1e-45, 1.0], F32)])
    with np.errstate(all="ignore"):
        lim = x * F32(2.0**-10)
        bx = x.view(U32)
        short = (bx <= 0x7F800000) & ((y.view(U32) & 0x7FFFFFFF) <= lim.view(U32))
        short_old = (x > 0) & (y <= lim) & (y >= -lim)
        zero = (bx == 0) & (y == 0)
        assert np.array_equal(short, short_old | zero)
        deg = dm.canonf(gc.atan2_small(y, x)) * F32(180.0 / math.pi)
        wide = ~short
        assert np.all(np.isnan(deg[wide]) | (np.abs(deg[wide]) > emit.WIDE_ANGLE_DEG))
        assert np.array_equal(deg[zero].view(U32), (y[zero] * F32(180.0 / math.pi)).view(U32))
        s = np.concatenate([rng.uniform(-2e-3, 2e-3, n).astype(F32), np.array([np.nan, 1.0, -1.0, 2.0**-10], F32),
                            np.nextafter(F32(2.0**-10), F32(1)) * np.ones(1, F32)])
        s_short = ((s.view(U32).astype(np.uint64) << 1) & 0xFFFFFFFF) <= 0x75000000
        assert np.array_equal(s_short, (s <= F32(2.0**-10)) & (s >= F32(-(2.0**-10))))
        sdeg = gc.asin_small(s) * F32(180.0 / math.pi)
        assert np.all(np.isnan(sdeg[~s_short]) | (np.abs(sdeg[~s_short]) > emit.WIDE_ANGLE_DEG))


def test_the_wide_branch_skips_the_network_only_for_a_narrow_envelope():
    a, cfg = load_artifact(None), flight_config()
    text = emit.controller_sources(a, cfg)["controller.c"]
    assert "finish(state, out, x, geometry_ok, valid, 0u)" in text
    assert not emit.wide_angles_fly(a.envelope.min, a.envelope.max)
    wide_min, wide_max = a.envelope.min.copy(), a.envelope.max.copy()
    wide_min[7], wide_max[7] = -1.0, 1.0
    assert emit.wide_angles_fly(wide_min, wide_max)
