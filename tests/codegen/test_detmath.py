"""The deterministic float32 math: numpy twin == C bit for bit, published ulp bounds, edge cases.

The C (codegen/csrc/sg_math.c) is built with the flight flags into a shared library in a temp
folder, together with test-only batch wrappers (one call per array instead of per element), and
loaded with cffi in ABI mode; the Cortex-M4F object is also run in Unicorn. Outputs are
compared as uint32 bit patterns; NaN as a class.
"""

from __future__ import annotations

import ast
import math
import shutil
import subprocess
from pathlib import Path

import cffi
import numpy as np
import pytest

from codegen import detmath as dm
from firmware.flags import ARM_CC, ARM_CPU, COMMON, with_opt

CSRC = Path(dm.__file__).resolve().parent / "csrc"
UNARY = ["tanhf", "expf", "logf", "sinf", "cosf", "asinf", "sqrtf"]
BINARY = ["atan2f", "powf_pos"]
F32 = np.float32

POWC_YS = {"g": 0.8, "gm1": -0.2, "half": 0.5, "m31": -31 / 32, "p31": 31 / 32, "tiny": 1e-3}
WRAPPERS = "\n".join(
    [f"void batch_{n}(const float *x, float *y, int n) {{ for (int i = 0; i < n; i++) "
     f"y[i] = sg_{n}(x[i]); }}" for n in [*UNARY, "logf_tab"]]
    + [f"void batch_{n}(const float *a, const float *b, float *y, int n) {{ for (int i = 0; "
       f"i < n; i++) y[i] = sg_{n}(a[i], b[i]); }}" for n in BINARY]
    + ["void batch_inline_tanhf(const float *x, float *y, int n) { for (int i = 0; i < n; i++) "
       "y[i] = sg_inline_tanhf(x[i]); }",
       "void batch_inline_tanhf_full(const float *x, float *y, int n) { for (int i = 0; i < n; i++) "
       "y[i] = sg_inline_tanhf_full(x[i]); }",
       "void batch_powf_fused(const float *a, const float *b, float *y, int n) { for (int i = 0; "
       "i < n; i++) y[i] = sg_powf_fused(a[i], b[i]); }",
       "void batch_powf_fused_08(const float *a, float *y, int n) { for (int i = 0; i < n; i++) "
       "y[i] = sg_powf_fused(a[i], 0x1.99999ap-1f); }",
       "void batch_powf_tab(const float *a, const float *b, float *y, int n) { for (int i = 0; "
       "i < n; i++) y[i] = sg_powf_tab(a[i], b[i]); }",
       "void batch_powf_tab_08(const float *a, float *y, int n) { for (int i = 0; i < n; i++) "
       "y[i] = sg_powf_tab(a[i], 0x1.99999ap-1f); }",
       *[f"static const sg_powc_t powc_{n} = {dm.powc_c_initializer(dm.powc_tables(y))};\n"
         f"void batch_powc_{n}(const float *x, float *y, int n) {{ for (int i = 0; i < n; i++) "
         f"y[i] = sg_powf_const(x[i], &powc_{n}); }}" for n, y in POWC_YS.items()]])


OPT_LEVELS = ["-O2", "-O0", "-Os"]  # the flight level and the benchmark levels (with_opt)


@pytest.fixture(scope="module", params=OPT_LEVELS)
def clib(request, tmp_path_factory):
    """sg_math.c + batch wrappers as a shared library built with the SPEC section 5 flags (at
    each optimisation level: the bits must not depend on it)."""
    d = tmp_path_factory.mktemp("sg_math")
    (d / "wrap.c").write_text('#include "sg_math.h"\n' + WRAPPERS + "\n")
    so = d / "libsgmath.so"
    subprocess.run(["gcc", *with_opt(COMMON, request.param), "-fPIC", "-shared", "-I", str(CSRC),
                    str(CSRC / "sg_math.c"), str(d / "wrap.c"), "-o", str(so)], check=True)
    ffi = cffi.FFI()
    ffi.cdef("\n".join([f"void batch_{n}(const float *, float *, int);"
                        for n in [*UNARY, "logf_tab", "inline_tanhf", "inline_tanhf_full", "powf_fused_08",
                                  "powf_tab_08", *[f"powc_{n}" for n in POWC_YS]]]
                       + [f"void batch_{n}(const float *, const float *, float *, int);"
                          for n in [*BINARY, "powf_fused", "powf_tab"]]))
    lib = ffi.dlopen(str(so))

    def call(name: str, *args: np.ndarray) -> np.ndarray:
        args = [np.ascontiguousarray(a, dtype=F32) for a in np.broadcast_arrays(*args)]
        out = np.empty_like(args[0])
        ptrs = [ffi.from_buffer("float[]", a) for a in args]
        getattr(lib, f"batch_{name}")(*ptrs, ffi.from_buffer("float[]", out), out.size)
        return out

    return call


def bits(u) -> np.ndarray:
    return np.asarray(u, dtype=np.uint32).view(F32)


def same(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Bit-identical, or both NaN (x86 and ARM default NaNs differ in sign)."""
    return (a.view(np.uint32) == b.view(np.uint32)) | (np.isnan(a) & np.isnan(b))


SPECIALS = bits([0x00000000, 0x80000000, 0x00000001, 0x80000001, 0x007FFFFF, 0x807FFFFF,
                 0x00800000, 0x80800000, 0x7F800000, 0xFF800000, 0x7FC00000, 0xFFC00000,
                 0x7F800001, 0x7F7FFFFF, 0xFF7FFFFF, 0x3F800000, 0xBF800000, 0x39800000,
                 0x397FFFFF, 0x41100000, 0x410FFFFF, 0x42B17217, 0x42B17218, 0xC2CFF1B4,
                 0xC2CFF1B5, 0x46000000, 0x46000001, 0x3F000000, 0x3EFFFFFF])

DENSE = {"tanhf": (-10.0, 10.0), "expf": (-105.0, 90.0), "logf": (0.0, 4.0),
         "sinf": (-8192.0, 8192.0), "cosf": (-8192.0, 8192.0), "asinf": (-1.0, 1.0),
         "sqrtf": (0.0, 100.0)}


def unary_inputs(name: str, rng: np.random.Generator, n: int = 60_000) -> np.ndarray:
    """Random bit patterns over all float32, dense values in the interesting range, specials,
    and every neighbour of the specials."""
    lo, hi = DENSE[name]
    near = (SPECIALS.view(np.uint32).astype(np.int64)[:, None] + np.arange(-3, 4)).ravel()
    near = (near % 2**32).astype(np.uint32)
    return np.concatenate([rng.integers(0, 2**32, n, dtype=np.uint64).astype(np.uint32).view(F32),
                           rng.uniform(lo, hi, n).astype(F32), SPECIALS, bits(near)])


@pytest.mark.parametrize("name", UNARY)
def test_twin_equals_c_unary(clib, name):
    x = unary_inputs(name, np.random.default_rng(UNARY.index(name)))
    assert x.size >= 100_000
    y_twin = getattr(dm, name)(x)
    y_c = clib(name, x)
    bad = ~same(y_twin, y_c)
    assert not bad.any(), (name, x[bad][:5].view(np.uint32), y_twin[bad][:5], y_c[bad][:5])


def test_inline_tanh_is_sg_tanhf_bit_for_bit(clib):
    """sg_inline_tanhf (sg_math.h, the network loop's tanh) and sg_tanhf give the same bits, NaN
    payloads included: every argument class of both paths, at each optimisation level."""
    rng = np.random.default_rng(7)
    x = np.concatenate([unary_inputs("tanhf", rng), SPECIALS, -SPECIALS,
                        rng.integers(0, 2**32, 60_000, dtype=np.uint64).astype(np.uint32).view(F32)])
    a, b = clib("inline_tanhf", x), clib("tanhf", x)
    assert np.array_equal(a.view(np.uint32), b.view(np.uint32))


def test_inline_tanh_full_is_sg_tanhf_bit_for_bit(clib):
    """sg_inline_tanhf_full (sg_math.h, the tanh law's torque: out-of-range arguments inline too)
    and sg_tanhf give the same bits, NaN payloads included, at each optimisation level."""
    rng = np.random.default_rng(8)
    near9 = bits((np.int64(0x41100000) + np.arange(-50, 51)).astype(np.uint32))
    x = np.concatenate([unary_inputs("tanhf", rng), SPECIALS, -SPECIALS, near9, -near9,
                        rng.integers(0, 2**32, 60_000, dtype=np.uint64).astype(np.uint32).view(F32)])
    a, b = clib("inline_tanhf_full", x), clib("tanhf", x)
    assert np.array_equal(a.view(np.uint32), b.view(np.uint32))


@pytest.mark.parametrize("name", BINARY)
def test_twin_equals_c_binary(clib, name):
    rng = np.random.default_rng(10 + BINARY.index(name))
    a = unary_inputs("tanhf", rng)
    b = rng.permutation(unary_inputs("expf", rng)[: a.size])
    if name == "powf_pos":
        a = np.abs(a)
    grid = np.concatenate([SPECIALS, -SPECIALS])
    ga, gb = (g.ravel() for g in np.meshgrid(grid, grid))  # every special pair, both orders
    a, b = np.concatenate([a, ga]), np.concatenate([b, gb])
    y_twin = getattr(dm, name)(a, b)
    y_c = clib(name, a, b)
    bad = ~same(y_twin, y_c)
    assert not bad.any(), (name, a[bad][:5], b[bad][:5], y_twin[bad][:5], y_c[bad][:5])


def ulp_error(y: np.ndarray, ref: np.ndarray) -> np.ndarray:
    """|y - ref| in ulp of the float32 result, ulp = 2^(max(floor(log2|ref|), -126) - 23)."""
    e = np.maximum(np.floor(np.log2(np.abs(ref))), -126.0)
    return np.abs(y.astype(np.float64) - ref) / np.exp2(e - 23.0)


REFERENCE = {"tanhf": np.tanh, "expf": np.exp, "logf": np.log, "sinf": np.sin, "cosf": np.cos,
             "asinf": np.arcsin, "sqrtf": np.sqrt}
SAMPLE_RANGE = {"tanhf": (-9.5, 9.5), "expf": (-103.0, 88.7), "logf": (1e-30, 1e30),
                "sinf": (-8192.0, 8192.0), "cosf": (-8192.0, 8192.0), "asinf": (-1.0, 1.0),
                "sqrtf": (0.0, 1e30)}


@pytest.mark.parametrize("name", UNARY)
def test_sampled_ulp_bound(name):
    rng = np.random.default_rng(100 + UNARY.index(name))
    lo, hi = SAMPLE_RANGE[name]
    u = rng.integers(0, 2**32, 400_000, dtype=np.uint64).astype(np.uint32).view(F32)
    x = np.concatenate([u, rng.uniform(lo, hi, 400_000).astype(F32),
                        rng.uniform(-1.0, 1.0, 200_000).astype(F32)])
    if name in ("sinf", "cosf"):
        x = x[np.abs(x) <= dm.TRIG_MAX_ARG]
    with np.errstate(all="ignore"):
        ref = REFERENCE[name](x.astype(np.float64))
    ok = np.isfinite(ref) & (ref != 0.0) & (np.abs(ref) < float(np.finfo(F32).max))
    err = ulp_error(getattr(dm, name)(x)[ok], ref[ok])
    assert err.max() <= dm.ULP_BOUND[name], (name, err.max(), x[ok][err.argmax()])


def test_sampled_ulp_bound_atan2():
    rng = np.random.default_rng(7)
    y = np.concatenate([rng.uniform(-5, 5, 500_000), rng.normal(0, 1e-20, 100_000)]).astype(F32)
    x = np.concatenate([rng.uniform(-5, 5, 500_000), rng.normal(0, 1e5, 100_000)]).astype(F32)
    ref = np.arctan2(y.astype(np.float64), x.astype(np.float64))
    ok = ref != 0.0
    err = ulp_error(dm.atan2f(y, x)[ok], ref[ok])
    i = err.argmax()
    assert err.max() <= dm.ULP_BOUND["atan2f"], (err.max(), y[ok][i], x[ok][i])


def test_sampled_pow_bound():
    """powf_pos: error <= POW_ULP_BASE + POW_ULP_PER_LOG * |y ln x| ulp (docs/math.md)."""
    rng = np.random.default_rng(8)
    x = np.exp2(rng.uniform(-60, 60, 500_000)).astype(F32)
    lim = rng.uniform(0, 88, x.size)
    y = (rng.uniform(-1, 1, x.size) * lim / np.maximum(np.abs(np.log(x.astype(np.float64))), 1e-3))
    y = y.astype(F32)
    ref = np.power(x.astype(np.float64), y.astype(np.float64))
    ok = np.isfinite(ref) & (ref > 1e-37) & (ref < 3e38)
    x, y, ref = x[ok], y[ok], ref[ok]
    err = ulp_error(dm.powf_pos(x, y), ref)
    size = np.abs(y.astype(np.float64) * np.log(x.astype(np.float64)))
    bound = dm.POW_ULP_BASE + dm.POW_ULP_PER_LOG * size
    assert (err <= bound).all(), (err[err > bound][:3], x[err > bound][:3], y[err > bound][:3])


def tansig(n: float) -> float:
    """MATLAB's definition, evaluated independently in float64."""
    return 2.0 / (1.0 + math.exp(-2.0 * n)) - 1.0


@pytest.mark.parametrize("n", [-8.5, -3.0, -1.0, -0.4, -1e-3, 1e-5, 0.25, 0.5, 0.9, 2.0, 5.5])
def test_tanh_matches_matlab_tansig(n):
    ref = tansig(float(F32(n)))
    got = dm.tanhf(n)
    assert ulp_error(np.atleast_1d(got), np.array([ref]))[0] <= 2.0, (n, got, ref)


NAN = float("nan")
INF = float("inf")
PI, PIO2, PIO4, PI3O4 = (bits(u) for u in (0x40490FDB, 0x3FC90FDB, 0x3F490FDB, 0x4016CBE4))
EDGES_UNARY = [
    ("tanhf", 0.0, 0.0), ("tanhf", -0.0, -0.0), ("tanhf", INF, 1.0), ("tanhf", -INF, -1.0),
    ("tanhf", NAN, NAN), ("tanhf", bits(1), bits(1)),
    ("tanhf", -bits(0x007FFFFF), -bits(0x007FFFFF)),
    ("tanhf", 9.0, 1.0), ("tanhf", -3.4e38, -1.0), ("tanhf", 2.0**-13, 2.0**-13),
    ("expf", 0.0, 1.0), ("expf", -0.0, 1.0), ("expf", bits(1), 1.0), ("expf", INF, INF),
    ("expf", -INF, 0.0), ("expf", NAN, NAN), ("expf", bits(0x42B17218), INF),
    ("expf", dm.EXP_UNF, bits(1)), ("expf", bits(0xC2CFF1B5), 0.0), ("expf", 1.0, bits(0x402DF854)),
    ("logf", 1.0, 0.0), ("logf", 0.0, -INF), ("logf", -0.0, -INF), ("logf", -1.0, NAN),
    ("logf", INF, INF), ("logf", -INF, NAN), ("logf", NAN, NAN), ("logf", -bits(1), NAN),
    ("logf", 2.0, bits(0x3F317218)),
    ("sinf", 0.0, 0.0), ("sinf", -0.0, -0.0), ("sinf", bits(1), bits(1)),
    ("sinf", -bits(1), -bits(1)),
    ("sinf", INF, NAN), ("sinf", -INF, NAN), ("sinf", NAN, NAN),
    ("cosf", 0.0, 1.0), ("cosf", -0.0, 1.0), ("cosf", INF, NAN), ("cosf", NAN, NAN),
    ("asinf", 0.0, 0.0), ("asinf", -0.0, -0.0), ("asinf", 1.0, PIO2), ("asinf", -1.0, -PIO2),
    ("asinf", bits(0x3F800001), NAN), ("asinf", -2.0, NAN), ("asinf", INF, NAN),
    ("asinf", NAN, NAN),
    ("sqrtf", 0.0, 0.0), ("sqrtf", -0.0, -0.0), ("sqrtf", 4.0, 2.0), ("sqrtf", -1.0, NAN),
    ("sqrtf", INF, INF), ("sqrtf", NAN, NAN),
]


@pytest.mark.parametrize("name,x,want", EDGES_UNARY)
def test_edge_cases_unary(clib, name, x, want):
    want = np.asarray(want, F32)
    for got in (getattr(dm, name)(x), clib(name, np.array([x], F32))[0]):
        assert same(np.asarray(got, F32), want), (name, x, got, want)


EDGES_ATAN2 = [  # C99 Annex F.9.1.4
    (0.0, 0.0, 0.0), (-0.0, 0.0, -0.0), (0.0, -0.0, PI), (-0.0, -0.0, -PI),
    (0.0, -1.0, PI), (-0.0, -1.0, -PI), (0.0, 1.0, 0.0), (-0.0, 1.0, -0.0),
    (-1.0, 0.0, -PIO2), (-1.0, -0.0, -PIO2), (1.0, 0.0, PIO2), (1.0, -0.0, PIO2),
    (1.0, -INF, PI), (-1.0, -INF, -PI), (1.0, INF, 0.0), (-1.0, INF, -0.0),
    (INF, 1.0, PIO2), (-INF, -1.0, -PIO2), (INF, -INF, PI3O4), (-INF, -INF, -PI3O4),
    (INF, INF, PIO4), (-INF, INF, -PIO4), (NAN, 1.0, NAN), (1.0, NAN, NAN), (NAN, NAN, NAN),
    (bits(1), -1.0, PI), (1e-30, 1e30, 1e-60), (-3e38, 1e-30, -PIO2),
]
EDGES_POW = [
    (0.0, 0.0, 1.0), (NAN, 0.0, 1.0), (INF, -0.0, 1.0), (2.0, 0.0, 1.0), (1.0, NAN, 1.0),
    (1.0, INF, 1.0), (1.0, -INF, 1.0), (0.0, 2.0, 0.0), (-0.0, 2.0, 0.0), (0.0, -2.0, INF),
    (-1.0, 2.0, NAN), (NAN, 2.0, NAN), (2.0, NAN, NAN), (INF, 2.0, INF), (INF, -1.0, 0.0),
    (0.5, INF, 0.0), (0.5, -INF, INF), (2.0, INF, INF), (2.0, -INF, 0.0), (2.0, 1000.0, INF),
]


@pytest.mark.parametrize("y,x,want", EDGES_ATAN2)
def test_edge_cases_atan2(clib, y, x, want):
    want = np.asarray(want, F32)
    for got in (dm.atan2f(y, x), clib("atan2f", np.array([y], F32), np.array([x], F32))[0]):
        assert same(np.asarray(got, F32), want), (y, x, got, want)


@pytest.mark.parametrize("x,y,want", EDGES_POW)
def test_edge_cases_pow(clib, x, y, want):
    want = np.asarray(want, F32)
    for got in (dm.powf_pos(x, y), clib("powf_pos", np.array([x], F32), np.array([y], F32))[0]):
        assert same(np.asarray(got, F32), want), (x, y, got, want)


def test_exp_overflow_underflow_thresholds():
    """Just inside the thresholds: finite and correctly scaled; just outside: Inf / +0."""
    top = dm.expf(dm.EXP_OVF)
    assert np.isfinite(top) and top > F32(3.4e38)
    assert dm.expf(np.nextafter(dm.EXP_OVF, F32(np.inf))) == np.inf
    assert dm.expf(np.nextafter(dm.EXP_UNF, F32(-np.inf))) == 0.0
    sub = dm.expf(np.linspace(-103.9, -87.5, 10_001, dtype=F32))  # results in the subnormals
    ref = np.exp(np.linspace(-103.9, -87.5, 10_001, dtype=F32).astype(np.float64))
    assert ulp_error(sub, ref).max() <= dm.ULP_BOUND["expf"]


def test_trig_outside_domain_is_bounded():
    rng = np.random.default_rng(5)
    x = np.concatenate([rng.uniform(8192.0, 3.4e38, 50_000), -rng.uniform(8192.0, 3.4e38, 50_000),
                        np.float32(3.4028235e38) * np.array([1.0, -1.0])]).astype(F32)
    for f in (dm.sinf, dm.cosf):
        y = f(x)
        assert np.isfinite(y).all() and (np.abs(y) <= 1.0).all()


def test_tanh_odd_and_monotone_on_grid():
    x = np.linspace(0.0, 10.0, 200_001, dtype=F32)
    y = dm.tanhf(x)
    assert (dm.tanhf(-x).view(np.uint32) == (-y).view(np.uint32)).all()
    assert (np.diff(y.astype(np.float64)) >= 0).all()


def test_shapes_scalars_and_dtypes():
    assert dm.tanhf(0.5).dtype == F32 and dm.tanhf(0.5).shape == ()
    x = np.linspace(-2, 2, 12, dtype=F32).reshape(3, 4)
    for name in UNARY:
        y = getattr(dm, name)(x)
        assert y.dtype == F32 and y.shape == (3, 4), name
    assert dm.atan2f(x, F32(1.0)).shape == (3, 4)
    assert dm.powf_pos(np.abs(x), 0.5).dtype == F32
    assert dm.tanhf(np.float64(0.3)).dtype == F32  # float64 in is converted, not promoted


def test_twin_uses_no_numpy_transcendentals():
    """SPEC 6: never np.tanh/np.exp/np.sin/..., @, dot or sum in the twin (sqrt is IEEE)."""
    tree = ast.parse(Path(dm.__file__).read_text())
    banned = {"tanh", "exp", "exp2", "expm1", "log", "log1p", "log2", "log10", "sin", "cos",
              "tan", "arcsin", "arccos", "arctan", "arctan2", "power", "float_power", "dot",
              "vdot", "sum", "matmul", "einsum", "hypot", "inner", "tensordot", "frexp", "ldexp"}
    used = {n.attr for n in ast.walk(tree) if isinstance(n, ast.Attribute)
            and isinstance(n.value, ast.Name) and n.value.id == "np"}
    assert not used & banned, used & banned
    assert not any(isinstance(n, ast.BinOp) and isinstance(n.op, ast.MatMult)
                   for n in ast.walk(tree))
    assert not any(isinstance(n, ast.Attribute) and n.attr in {"dot", "sum"}
                   for n in ast.walk(tree))


@pytest.mark.parametrize("opt", OPT_LEVELS)
def test_arm_object_has_no_libm_or_soft_double(tmp_path, opt):
    """sg_math.c compiles for the Cortex-M4F and references no libm / __aeabi_d* symbol."""
    assert shutil.which(ARM_CC), f"{ARM_CC} not installed (tools/setup.sh installs it)"
    obj = tmp_path / "sg_math.o"
    subprocess.run([ARM_CC, *with_opt(COMMON, opt), *ARM_CPU, "-c", str(CSRC / "sg_math.c"),
                    "-o", str(obj)], check=True)
    nm = subprocess.run(["arm-none-eabi-nm", str(obj)], capture_output=True, text=True,
                        check=True).stdout
    undefined = [ln.split()[-1] for ln in nm.splitlines() if ln.split()[0] == "U"]
    assert not undefined, undefined  # no libm, no __aeabi_d*, not even memcpy
    defined = {ln.split()[-1] for ln in nm.splitlines() if len(ln.split()) == 3}
    assert {f"sg_{n}" for n in UNARY + BINARY} <= defined


def _arm_runner(tmp_path, extra: list[str] | None = None):
    """Link sg_math.c for the Cortex-M4F at 0x08000000 and return call(name, *uint32 arrays)
    that runs one function per argument set in Unicorn (Cortex-M4 model, FZ = 0)."""
    from elftools.elf.elffile import ELFFile
    from unicorn import UC_ARCH_ARM, UC_MODE_MCLASS, UC_MODE_THUMB, Uc
    from unicorn import arm_const as a

    elf = tmp_path / "sg_math.elf"
    subprocess.run([ARM_CC, *COMMON, *ARM_CPU, "-nostdlib", "-nostartfiles",
                    "-Wl,-Ttext=0x08000000", "-Wl,-e,sg_tanhf", "-I", str(CSRC), str(CSRC / "sg_math.c"),
                    *(extra or []), "-o", str(elf)], check=True)
    mu = Uc(UC_ARCH_ARM, UC_MODE_THUMB | UC_MODE_MCLASS)
    mu.ctl_set_cpu_model(a.UC_CPU_ARM_CORTEX_M4)
    for base, size in ((0x08000000, 0x100000), (0x20000000, 0x20000), (0x0FFFF000, 0x1000)):
        mu.mem_map(base, size)
    with open(elf, "rb") as f:
        e = ELFFile(f)
        for seg in e.iter_segments():
            if seg["p_type"] == "PT_LOAD":
                mu.mem_write(seg["p_paddr"], seg.data())
        syms = {s.name: s["st_value"] & ~1 for s in e.get_section_by_name(".symtab").iter_symbols()}
    mu.reg_write(a.UC_ARM_REG_FPEXC, 0x40000000)
    stop = 0x0FFFFF00

    def call(name: str, *args: np.ndarray) -> np.ndarray:
        out = np.empty(len(args[0]), np.uint32)
        for i in range(out.size):
            for reg, arg in zip((a.UC_ARM_REG_S0, a.UC_ARM_REG_S1), args):
                mu.reg_write(reg, int(arg[i]))
            mu.reg_write(a.UC_ARM_REG_SP, 0x20010000)
            mu.reg_write(a.UC_ARM_REG_LR, stop | 1)
            mu.emu_start(syms[f"sg_{name}"] | 1, stop)
            out[i] = mu.reg_read(a.UC_ARM_REG_S0)
        return out.view(F32)

    return call


def test_arm_emulated_equals_twin(tmp_path):
    """The Cortex-M4F object, executed instruction by instruction, gives the twin's bits."""
    call = _arm_runner(tmp_path)
    rng = np.random.default_rng(11)
    for name in UNARY:
        x = np.concatenate([unary_inputs(name, rng, 1_500), SPECIALS])
        y_arm = call(name, x.view(np.uint32))
        bad = ~same(getattr(dm, name)(x), y_arm)
        assert not bad.any(), (name, x[bad][:5])
    for name in BINARY:
        p, q = unary_inputs("tanhf", rng, 1_500), unary_inputs("expf", rng, 1_500)
        p = np.abs(p) if name == "powf_pos" else p
        y_arm = call(name, p.view(np.uint32), q.view(np.uint32))
        bad = ~same(getattr(dm, name)(p, q), y_arm)
        assert not bad.any(), (name, p[bad][:5], q[bad][:5])


def test_arm_sqrt_fallback_equals_vsqrt(tmp_path):
    """sg_sqrtf built with -DSG_NO_BUILTINS (the C99 integer root, issue 25) gives VSQRT's bits on
    the Cortex-M4F, NaNs included (its default NaN and quieted payloads are the FPU's own)."""
    (tmp_path / "builtin").mkdir()
    (tmp_path / "c99").mkdir()
    vsqrt = _arm_runner(tmp_path / "builtin")
    c99 = _arm_runner(tmp_path / "c99", ["-DSG_NO_BUILTINS"])
    rng = np.random.default_rng(25)
    near = (SPECIALS.view(np.uint32).astype(np.int64)[:, None] + np.arange(-3, 4)).ravel() % 2**32
    x = np.concatenate([near.astype(np.uint32), rng.integers(0, 2**32, 3_000, dtype=np.uint64).astype(np.uint32),
                        rng.integers(0x3F800000, 0x40800000, 1_000, dtype=np.uint64).astype(np.uint32)])
    nm = subprocess.run(["arm-none-eabi-nm", str(tmp_path / "c99" / "sg_math.elf")], capture_output=True, text=True,
                        check=True).stdout
    assert " sg_sqrtf_c99" in nm                     # the fallback is what runs
    want, got = vsqrt("sqrtf", x), c99("sqrtf", x)
    bad = want.view(np.uint32) != got.view(np.uint32)
    assert not bad.any(), [hex(v) for v in x[bad][:5]]


# ---------------------------------------------------------------- sg_powf_fused (sg_math.h)

def powf_fused_inputs(rng: np.random.Generator, n: int = 120_000) -> tuple[np.ndarray, np.ndarray]:
    """Fast-path pairs (x log-uniform over the positive normals, y in [-4, 4] scaled so that
    |y log2 x| < 125 mostly, and y = 0.8 on (1e-8, 1]), then special pairs and random bits."""
    x = np.exp2(rng.uniform(-126, 128, n)).astype(F32)
    y = (rng.uniform(-4, 4, n) * np.minimum(1.0, 124.0 / np.maximum(np.abs(np.log2(x.astype(np.float64))), 1.0)))
    x2 = np.exp2(rng.uniform(-26.6, 0, n // 2)).astype(F32)
    grid = np.concatenate([SPECIALS, -SPECIALS, F32([0.8, 0.5, 2.0, -1.0, 125.0, 1e-30])])
    ga, gb = (g.ravel() for g in np.meshgrid(grid, grid))
    rx = rng.integers(0, 2**32, 20_000, dtype=np.uint64).astype(np.uint32).view(F32)
    ry = rng.integers(0, 2**32, 20_000, dtype=np.uint64).astype(np.uint32).view(F32)
    return (np.concatenate([x, x2, ga, rx, np.abs(rx)]),
            np.concatenate([y.astype(F32), np.full(x2.size, F32(0.8)), gb, ry, rng.uniform(-2, 2, 20_000).astype(F32)]))


def test_powf_fused_twin_equals_c(clib):
    """sg_powf_fused == detmath.powf_fused bit for bit on >= 1e5 fast-path pairs, every special
    pair and random bit patterns, at each optimisation level; also with a constant y (0.8) as
    the generated tanh law calls it (the y split is then folded by the compiler)."""
    x, y = powf_fused_inputs(np.random.default_rng(21))
    assert x.size >= 100_000
    y_twin, y_c = dm.powf_fused(x, y), clib("powf_fused", x, y)
    bad = ~same(y_twin, y_c)
    assert not bad.any(), (x[bad][:5], y[bad][:5], y_twin[bad][:5], y_c[bad][:5])
    x8 = np.concatenate([np.abs(x), x])
    bad = ~same(dm.powf_fused(x8, F32(0.8)), clib("powf_fused_08", x8))
    assert not bad.any(), x8[bad][:5]


def pow_fast_path_samples(rng):
    """(x, y, float64 x**y) for x over all positive normals, |y| <= 4, |y log2 x| < 124 (fast path)."""
    x = np.exp2(rng.uniform(-126, 128, 1_000_000)).astype(F32)
    y = (rng.uniform(-4, 4, x.size) * np.minimum(1.0, 120.0 / np.maximum(np.abs(np.log2(x.astype(np.float64))), 1.0)))
    y = y.astype(F32)
    with np.errstate(all="ignore"):
        t = y.astype(np.float64) * np.log2(x.astype(np.float64))
    ok = np.abs(t) < 124.0
    x, y = x[ok], y[ok]
    ref = np.power(x.astype(np.float64), y.astype(np.float64))
    return x, y, ref


def test_powf_fused_sampled_ulp_bound():
    """Fast path: error <= POWF_FUSED_ULP_BASE + POWF_FUSED_ULP_PER_Y |y| ulp on 1.2e6 samples
    (docs/math.md); y = 0.8 (the tanh law's gamma) within 1.7 ulp on (1e-8, 1e4]."""
    rng = np.random.default_rng(22)
    x, y, ref = pow_fast_path_samples(rng)
    err = ulp_error(dm.powf_fused(x, y), ref)
    bound = dm.POWF_FUSED_ULP_BASE + dm.POWF_FUSED_ULP_PER_Y * np.abs(y.astype(np.float64))
    assert (err <= bound).all(), (err[err > bound][:3], x[err > bound][:3], y[err > bound][:3])
    g = F32(0.8)
    x = np.exp(rng.uniform(np.log(1e-8), np.log(1e4), 200_000)).astype(F32)
    err = ulp_error(dm.powf_fused(x, g), np.power(x.astype(np.float64), float(g)))
    assert err.max() <= 1.7, err.max()


EDGES_POW_FUSED = [(0.0, 0.8, 0.0), (-0.0, 0.8, 0.0), (1.0, 0.8, 1.0), (1.0, -3.0, 1.0),
                   (2.0, 0.0, 1.0), (4.0, 0.5, 2.0), (0.25, 0.5, 0.5), (8.0, -1.0, 0.125),
                   (-2.0, 0.8, np.nan), (np.inf, 0.8, np.inf), (np.nan, 0.8, np.nan),
                   (2.0, np.nan, np.nan), (2.0**-130, 0.8, None), (2.0, 200.0, np.inf)]


@pytest.mark.parametrize("x,y,want", EDGES_POW_FUSED)
def test_edge_cases_powf_fused(clib, x, y, want):
    """Special values (through sg_powf_pos) and exact powers of two on the fast path."""
    got_twin = dm.powf_fused(x, y)
    got_c = clib("powf_fused", np.array([x], F32), np.array([y], F32))[0]
    assert same(np.asarray(got_twin, F32), np.asarray(got_c, F32))
    if want is None:  # subnormal x: the sg_powf_pos path
        assert same(np.asarray(got_twin, F32), dm.powf_pos(x, y))
    else:
        assert same(np.asarray(got_twin, F32), np.asarray(want, F32)), (x, y, got_twin, want)


def test_arm_emulated_powf_fused_equals_twin(tmp_path):
    """The Cortex-M4F build of sg_powf_fused (through an out-of-line wrapper) gives the twin's bits."""
    wrap = tmp_path / "powf_fused_wrap.c"
    wrap.write_text('#include "sg_math.h"\nfloat sg_powf_fused_call(float x, float y);\n'
                    "float sg_powf_fused_call(float x, float y) { return sg_powf_fused(x, y); }\n")
    call = _arm_runner(tmp_path, extra=[str(wrap)])
    rng = np.random.default_rng(23)
    x, y = powf_fused_inputs(rng, 2_000)
    i = rng.choice(x.size, 4_000, replace=False)
    x = np.concatenate([x[:3_000], x[i]])
    y = np.concatenate([y[:3_000], y[i]])
    y_arm = call("powf_fused_call", x.view(np.uint32), y.view(np.uint32))
    bad = ~same(dm.powf_fused(x, y), y_arm)
    assert not bad.any(), (x[bad][:5], y[bad][:5])


# ---------------------------------------------------------------- sg_powf_tab (sg_math.h)

def test_powf_tab_twin_equals_c(clib):
    """sg_powf_tab == detmath.powf_tab bit for bit on >= 1e5 fast-path pairs, every special pair
    and random bit patterns, at each optimisation level; also with a constant y (0.8)."""
    x, y = powf_fused_inputs(np.random.default_rng(31))
    assert x.size >= 100_000
    y_twin, y_c = dm.powf_tab(x, y), clib("powf_tab", x, y)
    bad = ~same(y_twin, y_c)
    assert not bad.any(), (x[bad][:5], y[bad][:5], y_twin[bad][:5], y_c[bad][:5])
    x8 = np.concatenate([np.abs(x), x])
    bad = ~same(dm.powf_tab(x8, F32(0.8)), clib("powf_tab_08", x8))
    assert not bad.any(), x8[bad][:5]


def test_powf_tab_sampled_ulp_bound():
    """Fast path: error <= POWF_TAB_ULP_BASE + POWF_TAB_ULP_PER_Y |y| ulp on 1e6 samples
    (docs/math.md); the tanh law's exponents (0.8, -0.2) within 1.4 ulp on (1e-8, 1e4]."""
    rng = np.random.default_rng(32)
    x, y, ref = pow_fast_path_samples(rng)
    err = ulp_error(dm.powf_tab(x, y), ref)
    bound = dm.POWF_TAB_ULP_BASE + dm.POWF_TAB_ULP_PER_Y * np.abs(y.astype(np.float64))
    assert (err <= bound).all(), (err[err > bound][:3], x[err > bound][:3], y[err > bound][:3])
    x = np.exp(rng.uniform(np.log(1e-8), np.log(1e4), 200_000)).astype(F32)
    for g in (F32(0.8), F32(-0.2)):
        err = ulp_error(dm.powf_tab(x, g), np.power(x.astype(np.float64), float(g)))
        assert err.max() <= 1.4, (g, err.max())


@pytest.mark.parametrize("x,y,want", EDGES_POW_FUSED)
def test_edge_cases_powf_tab(clib, x, y, want):
    """Special values (through sg_powf_pos) and exact powers of two on the fast path."""
    got_twin = dm.powf_tab(x, y)
    got_c = clib("powf_tab", np.array([x], F32), np.array([y], F32))[0]
    assert same(np.asarray(got_twin, F32), np.asarray(got_c, F32))
    if want is None:
        assert same(np.asarray(got_twin, F32), dm.powf_pos(x, y))
    else:
        assert same(np.asarray(got_twin, F32), np.asarray(want, F32)), (x, y, got_twin, want)


# ---------------------------------------------------------------- sg_powf_const (sg_math.h)

def test_powf_const_twin_equals_c(clib):
    """sg_powf_const == detmath.powf_const bit for bit for six exponents (the tanh law's 0.8 and
    -0.2, the ends +-31/32), >= 1e5 positive normals, special values and random bit patterns."""
    x, _ = powf_fused_inputs(np.random.default_rng(41))
    assert x.size >= 100_000
    x = np.concatenate([x, np.abs(x), SPECIALS, -SPECIALS])
    for n, y in POWC_YS.items():
        y_twin, y_c = dm.powf_const(x, dm.powc_tables(y)), clib(f"powc_{n}", x)
        bad = ~same(y_twin, y_c)
        assert not bad.any(), (n, x[bad][:5], y_twin[bad][:5], y_c[bad][:5])


def test_powf_const_sampled_ulp_bound():
    """Error <= POWC_ULP ulp on 1e6 positive normals (log-uniform) per exponent; edge cases:
    +0 and subnormal x give +0 when y > 0 (no call; the true value is below 2^(-126 y)), every
    other x that is not a positive normal takes powf_pos (1^y is not exact: c_i != 1)."""
    rng = np.random.default_rng(42)
    x = np.exp2(rng.uniform(-126, 128, 1_000_000)).astype(F32)
    for y in [*POWC_YS.values(), 0.1, -0.6]:
        t = dm.powc_tables(y)
        err = ulp_error(dm.powf_const(x, t), np.power(x.astype(np.float64), float(t.y)))
        assert err.max() <= dm.POWC_ULP, (y, err.max())
    t = dm.powc_tables(0.8)
    for xs in (-0.0, -2.0, -(2.0**-130), np.inf, np.nan):
        assert same(np.asarray(dm.powf_const(xs, t), F32), np.asarray(dm.powf_pos(xs, t.y), F32))
    tiny = np.array([0.0, 2.0**-149, 2.0**-130, np.nextafter(F32(2.0**-126), F32(0))], F32)
    assert np.array_equal(dm.powf_const(tiny, t).view(np.uint32), np.zeros(4, np.uint32))
    assert np.all(np.power(tiny.astype(np.float64), float(t.y)) < 2.0 ** (-126 * 0.8))
    t_neg = dm.powc_tables(-0.2)  # y < 0: 0 and subnormals keep powf_pos (+Inf at 0, finite above)
    assert np.array_equal(dm.powf_const(tiny, t_neg).view(np.uint32), dm.powf_pos(tiny, t_neg.y).view(np.uint32))
    with pytest.raises(ValueError):
        dm.powc_tables(1.0)
    assert np.isfinite(dm.powc_tables(1.0 - 2.0**-24).ek).all()


# ---------------------------------------------------------------- sg_logf_tab (sg_math.h)

def test_logf_tab_twin_equals_c(clib):
    """sg_logf_tab == detmath.logf_tab bit for bit on >= 1e5 positive normals (log-uniform, and
    1 - 10^-8 .. 1), special values and random bit patterns, at each optimisation level."""
    rng = np.random.default_rng(51)
    x = np.concatenate([np.exp2(rng.uniform(-126, 128, 100_000)).astype(F32),
                        (1.0 - np.exp(rng.uniform(np.log(1e-8), 0.0, 50_000))).astype(F32), SPECIALS, -SPECIALS,
                        rng.integers(0, 2**32, 50_000, dtype=np.uint64).astype(np.uint32).view(F32)])
    y_twin, y_c = dm.logf_tab(x), clib("logf_tab", x)
    bad = ~same(y_twin, y_c)
    assert not bad.any(), (x[bad][:5], y_twin[bad][:5], y_c[bad][:5])


def test_logf_tab_sampled_ulp_bound():
    """Error <= LOGF_TAB_ULP ulp on 2e6 positive normals (uniform bit patterns and near 1);
    ln 1 = 0 exactly; x not a positive normal gives logf(x)."""
    rng = np.random.default_rng(52)
    x = np.concatenate([rng.integers(0x00800000, 0x7F800000, 1_000_000, dtype=np.uint64).astype(np.uint32).view(F32),
                        (1.0 - np.exp(rng.uniform(np.log(1e-8), 0.0, 500_000))).astype(F32),
                        np.exp(rng.uniform(-0.1, 0.1, 500_000)).astype(F32)])
    x = x[x != F32(1.0)]
    err = ulp_error(dm.logf_tab(x), np.log(x.astype(np.float64)))
    assert err.max() <= dm.LOGF_TAB_ULP, err.max()
    assert dm.logf_tab(1.0) == F32(0.0)
    for xs in (0.0, -0.0, -2.0, np.inf, np.nan, 2.0**-130):
        assert same(np.asarray(dm.logf_tab(xs), F32), np.asarray(dm.logf(xs), F32))
