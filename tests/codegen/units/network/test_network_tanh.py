"""The network path's tansig (network.c: <name>_tanh_rows, <name>_tanh, <name>_tanh_pair) is sg_tanhf
bit for bit: the signed table's identity over every argument in it (numpy, IEEE float32 like the C),
and the C helpers themselves on x86 against sg_tanhf, every argument class and every pair of
classes (both in the table, one, none)."""
from __future__ import annotations

import subprocess

import cffi
import numpy as np
import pytest

from codegen import artifact as art
from codegen import detmath
from codegen.units.network import emit
from firmware.flags import COMMON

F32 = np.float32
U32 = np.uint32
LO, HI = 0x39800000, 0x41800000  # |x| in [2^-12, 16): the arguments the table holds


def _index(u: np.ndarray) -> np.ndarray:
    """sg_tanh_index: interval of |x| (wraps around below 2^-12)."""
    return ((u << U32(1)) >> U32(21)) - U32((127 - 12) << 3)


def _table_tanh(x: np.ndarray) -> np.ndarray:
    """The C's formula: row middle + (i ^ sign mask), t = x - row[0], the Horner chain in its order."""
    rows = detmath.tanh_rows()
    u = x.view(U32)
    i = _index(u)
    assert (i < detmath.TANH_HALF).all()
    k = (i ^ (U32(0) - (u >> U32(31)))).view(np.int32).astype(np.int64) + detmath.TANH_HALF
    r = rows[k]
    t = x - r[:, 0]
    p = r[:, 5] * t
    p = p + r[:, 4]
    p = p * t
    p = p + r[:, 3]
    p = p * t
    p = p + r[:, 2]
    p = p * t
    return p + r[:, 1]


def test_tanh_rows_layout():
    rows = detmath.tanh_rows()
    n = detmath.TANH_TABLE.shape[0]
    half = detmath.TANH_HALF
    assert rows.shape == (2 * half, detmath.TANH_COLS) and rows.dtype == F32
    pos, neg = rows[half:], rows[:half][::-1]
    assert np.array_equal(pos[:n, :6], detmath.TANH_TABLE)  # sg_tanh_tab itself for x >= 0
    assert np.array_equal(neg[:, :6], pos[:, :6] * detmath.TANH_MIRROR_SIGNS)
    assert (pos[n:, 1] == 1).all() and not pos[n:, [0, 2, 3, 4, 5]].any()  # 9 <= |x| < 16: exactly 1
    assert not rows[:, 6:].any()


def _check_range(start: int, stop: int, step: int = 1) -> None:
    for s in range(start, stop, 1 << 23):
        u = np.arange(s, min(s + (1 << 23), stop), step, dtype=U32)
        for x in (u.view(F32), (u | U32(0x80000000)).view(F32)):
            bad = _table_tanh(x).view(U32) != detmath.tanhf(x).view(U32)
            assert not bad.any(), x[bad][:5]


def test_signed_rows_give_sg_tanhf_sampled():
    """Every 61st argument of the table's range, both signs, and every one near its ends and near 9."""
    _check_range(LO, HI, 61)
    for edge in (LO, 0x41100000, HI - 4096):
        _check_range(edge, edge + 4096)


@pytest.mark.slow
def test_signed_rows_give_sg_tanhf_for_every_argument_in_the_table():
    """Exhaustive: all 2 x 2^27 float32 with 2^-12 <= |x| < 16 (about a minute)."""
    _check_range(LO, HI)


# Each loop shape emits only the tanh helpers it calls (clang's -Wunused-function): the one-neuron
# helper network_tanh with an odd hidden count (41), the pair helper with an even one (40).
WRAPPERS = {41: """
void test_tanh(const float *x, float *y, int n)
{
    network_rows_t mid = &network_tanh_rows[NETWORK_TANH_HALF];
    int i;
    for (i = 0; i < n; i++) {
        y[i] = network_tanh(mid, x[i]);
    }
}

void test_sg_tanhf(const float *x, float *y, int n)
{
    int i;
    for (i = 0; i < n; i++) {
        y[i] = sg_tanhf(x[i]);
    }
}
""", 40: """
void test_tanh_pair(const float *a, const float *b, float *ya, float *yb, int n)
{
    network_rows_t mid = &network_tanh_rows[NETWORK_TANH_HALF];
    int i;
    for (i = 0; i < n; i++) {
        const network_pair_t r = network_tanh_pair(mid, a[i], b[i]);
        ya[i] = r.a;
        yb[i] = r.b;
    }
}
"""}
CDEFS = {41: "void test_tanh(const float *, float *, int); void test_sg_tanhf(const float *, float *, int);",
         40: "void test_tanh_pair(const float *, const float *, float *, float *, int);"}


def _network_lib(d, n_hidden: int):
    """network.c of a 12-n_hidden-3 network (with test wrappers appended: its helpers are static) +
    sg_math.c, x86, flight flags."""
    sources = emit.network_sources(art.random_artifact((12, n_hidden, 3), seed=1))
    sources["network.c"] += WRAPPERS[n_hidden]
    for name, text in sources.items():
        (d / name).write_text(text)
    so = d / "libnet.so"
    subprocess.run(["gcc", *COMMON, "-Wno-missing-prototypes", "-fPIC", "-shared", "-I", str(d),
                    str(d / "network.c"), str(d / "sg_math.c"), "-o", str(so)], check=True)
    ffi = cffi.FFI()
    ffi.cdef(CDEFS[n_hidden])
    return ffi, ffi.dlopen(str(so))


@pytest.fixture(scope="module")
def clib(tmp_path_factory):
    """The one-neuron helper, the pair helper and sg_tanhf, as numpy functions."""
    (ffi1, one), (ffi2, two) = (_network_lib(tmp_path_factory.mktemp(f"network_tanh{n}"), n) for n in (41, 40))

    def tanh(x):
        y = np.empty_like(x)
        one.test_tanh(ffi1.from_buffer("float[]", x), ffi1.from_buffer("float[]", y), x.size)
        return y

    def pair(a, b):
        ya, yb = np.empty_like(a), np.empty_like(b)
        two.test_tanh_pair(*(ffi2.from_buffer("float[]", v) for v in (a, b, ya, yb)), a.size)
        return ya, yb

    def sg(x):
        y = np.empty_like(x)
        one.test_sg_tanhf(ffi1.from_buffer("float[]", x), ffi1.from_buffer("float[]", y), x.size)
        return y

    return tanh, pair, sg


def _arguments(rng) -> np.ndarray:
    """Random bits, dense values across the table and beyond it, the class edges and their neighbours,
    specials (±0, subnormals, ±Inf, NaNs with payloads)."""
    edges = np.array([0, 1, 0x007FFFFF, 0x00800000, LO, 0x41100000, HI, 0x7F7FFFFF, 0x7F800000,
                      0x7F800001, 0x7FC00000, 0x7FFFFFFF], dtype=np.int64)
    near = ((edges[:, None] + np.arange(-3, 4)) % 2**32).astype(U32).ravel()
    near = np.concatenate([near, near | U32(0x80000000)])
    return np.concatenate([rng.integers(0, 2**32, 50_000, dtype=np.uint64).astype(U32).view(F32),
                           rng.uniform(-20, 20, 50_000).astype(F32), near.view(F32)])


def test_c_tanh_is_sg_tanhf_bit_for_bit(clib):
    tanh, _pair, sg = clib
    x = _arguments(np.random.default_rng(3))
    assert np.array_equal(tanh(x).view(U32), sg(x).view(U32))


def test_c_tanh_pair_is_sg_tanhf_bit_for_bit_for_every_pair_of_classes(clib):
    """Both in the table (the interleaved chains), a in and b out, a out and b in, both out."""
    _tanh, pair, sg = clib
    rng = np.random.default_rng(4)
    x = _arguments(rng)
    inside = (_index(x.view(U32)) < detmath.TANH_HALF)
    ins, outs = x[inside], x[~inside]
    assert ins.size > 1000 and outs.size > 1000
    for a_pool, b_pool in ((ins, ins), (ins, outs), (outs, ins), (outs, outs), (x, x)):
        a = rng.choice(a_pool, 20_000)
        b = rng.choice(b_pool, 20_000)
        ya, yb = pair(a, b)
        assert np.array_equal(ya.view(U32), sg(a).view(U32))
        assert np.array_equal(yb.view(U32), sg(b).view(U32))
