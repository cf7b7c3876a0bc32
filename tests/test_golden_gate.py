"""Bit-exact gate: golden model == x86 C on uint32 bit patterns; the gate's own sensitivity;
vector coverage; golden vs float64 reference bound; x86 build cache; c-eval / verify CLI."""
import inspect
import os
import subprocess
import sys
import textwrap

import numpy as np
import pytest

import host.cli as cli
from codegen import artifact as art
from codegen.units.network import reference
from codegen import bitcompare
from codegen.units.network import golden, vectors
from firmware import x86
from firmware.errors import FirmwareError
from host.cli import c_eval

GATE_VECTORS = 20_000
# Golden vs the float64 reference of the same network, in-envelope inputs: |error| <= this
# fraction of the output data range (measured ~2.5e-7 for random 12-40-3 artifacts).
REFERENCE_BOUND = 1e-6


@pytest.fixture(scope="module")
def net12():
    a = art.random_artifact((12, 40, 3), seed=1)
    return a, x86.network_library(a)


@pytest.fixture(scope="module")
def net5():
    a = art.random_artifact((5, 17, 2), seed=1)
    return a, x86.network_library(a)


def assert_bits_equal(expected, actual):
    """uint32 equality everywhere except where both are NaN (any NaN equals any NaN)."""
    e, a = expected.view(np.uint32), actual.view(np.uint32)
    both_nan = np.isnan(expected) & np.isnan(actual)
    bad = (e != a) & ~both_nan
    assert not bad.any(), f"{bad.sum()} mismatches, first at {np.argwhere(bad)[:3].tolist()}"


@pytest.mark.parametrize("which, seed", [("net12", 0), ("net5", 1)])
def test_gate_golden_equals_x86_bit_for_bit(request, which, seed):
    a, lib = request.getfixturevalue(which)
    vs = vectors.gate_vectors(a.envelope, GATE_VECTORS, seed)
    y_golden, y_c = golden.network_eval(a, vs.x), lib.eval(vs.x)
    assert_bits_equal(y_golden, y_c)
    assert bitcompare.compare(y_golden, y_c).ok
    # The gate exercised every class, including non-finite outputs.
    assert set(vs.counts().values()) != {0} and np.isnan(y_c).any() and np.isfinite(y_c).mean() > 0.5


def test_each_stage_is_bit_exact(net12):
    a, lib = net12
    x = vectors.gate_vectors(a.envelope, 5_000, 3).x
    xn = golden.normalise(a, x)
    assert_bits_equal(xn, lib.normalise(x))
    yn = golden.mlp(a, xn)
    assert_bits_equal(yn, lib.mlp(xn))
    assert_bits_equal(golden.denormalise(a, yn), lib.denormalise(yn))


def test_gate_detects_a_one_ulp_weight_change(net12):
    a, lib = net12
    W1 = a.W1.copy()
    W1[7, 4] = np.nextafter(W1[7, 4], np.float32(np.inf))
    off = art.from_arrays(W1, a.b1, a.W2, a.b2, a.input_map.xmin, a.input_map.xmax,
                          a.output_map.xmin, a.output_map.xmax, envelope=a.envelope)
    x = vectors.gate_vectors(a.envelope, 2_000, 0).x
    result = bitcompare.compare(golden.network_eval(off, x), lib.eval(x))
    assert result.n_mismatches > 0
    assert "0x" in result.report()[1] and "!=" in result.report()[1]


def test_gate_detects_a_reordered_sum(net12):
    """Adding the bias last instead of first (same maths, other rounding) must not pass."""
    a, lib = net12
    xn = golden.normalise(a, vectors.gate_vectors(a.envelope, 2_000, 0).x)
    acc = np.zeros((xn.shape[0], a.n_hidden), np.float32)
    with np.errstate(all="ignore"):  # the vectors include Inf/NaN rows
        for i in range(a.n_in):
            acc = acc + a.W1[:, i] * xn[:, i, None]
    reordered = golden.output_layer(a, golden.tansig(acc + a.b1))
    assert bitcompare.compare(reordered, lib.mlp(xn)).n_mismatches > 100


def test_golden_is_close_to_the_float64_reference(net12):
    a, _ = net12
    vs = vectors.gate_vectors(a.envelope, GATE_VECTORS, 5)
    inside = vectors.inside_mask(a.envelope, vs.x)
    assert inside.sum() > GATE_VECTORS // 2
    err = np.abs(golden.network_eval(a, vs.x[inside]) - reference.reference_eval64(a, vs.x[inside]))
    span = a.output_map.xmax - a.output_map.xmin
    assert (err / span).max() <= REFERENCE_BOUND
    assert err.max() > 0  # float32 really differs from float64: the comparison is not vacuous


def test_golden_refuses_float64_and_uses_no_reordering_or_library_math():
    a = art.random_artifact((5, 17, 2), 0)
    with pytest.raises(ValueError, match="float32"):
        golden.network_eval(a, np.zeros((3, 5)))
    for fn in (golden.normalise, golden.hidden_preactivation, golden.tansig, golden.output_layer,
               golden.denormalise, golden.network_eval):
        src = inspect.getsource(fn)
        for banned in (" @ ", ".dot(", "np.sum", ".sum(", "np.tanh", "np.exp", "einsum", "matmul", "float64"):
            assert banned not in src, (fn.__name__, banned)


# ----------------------------------------------------------------------------- vectors, bitcompare

def test_vectors_cover_bounds_ulps_and_every_special_value_in_every_position():
    env = art.random_artifact((12, 40, 3), 0).envelope
    vs = vectors.gate_vectors(env, 10_000, 9)
    x, kind = vs.x, vs.kind
    assert x.dtype == np.float32 and x.shape == (10_000, 12) and sum(vs.counts().values()) == 10_000
    inside = x[kind == vectors.INSIDE]
    assert np.all((inside >= env.min) & (inside <= env.max))
    bound = x[kind == vectors.BOUND]
    for p in range(12):
        for v in (env.min[p], env.max[p], np.nextafter(env.min[p], np.float32(-1e30)),
                  np.nextafter(env.max[p], np.float32(1e30)), np.nextafter(env.max[p], np.float32(-1e30))):
            assert np.any(bound[:, p].view(np.uint32) == np.float32(v).view(np.uint32)), (p, v)
    assert not vectors.inside_mask(env, x[kind == vectors.OUTSIDE]).any()
    special = x[kind == vectors.SPECIAL]
    for p in range(12):
        for v in vectors.SPECIAL_VALUES:
            assert np.any(special[:, p].view(np.uint32) == v.view(np.uint32)), (p, v)
    again = vectors.gate_vectors(env, 10_000, 9)
    assert np.array_equal(again.x.view(np.uint32), x.view(np.uint32))
    assert not np.array_equal(vectors.gate_vectors(env, 10_000, 10).x.view(np.uint32), x.view(np.uint32))


@pytest.mark.parametrize("shape", [(5, 17, 2), (1, 3, 1)])
def test_vector_classes_hold_for_synthetic_envelopes(shape):
    """Narrow spans far from zero: `outside` rows must still be outside after float32 rounding."""
    env = art.random_artifact(shape, 2).envelope
    vs = vectors.gate_vectors(env, 5_000, 1)
    inside = vectors.inside_mask(env, vs.x)
    assert inside[vs.kind == vectors.INSIDE].all()
    assert not inside[vs.kind == vectors.OUTSIDE].any()


def test_bitcompare_nan_is_a_class_signed_zero_is_not():
    x86_nan = np.uint32([0xFFC00000]).view(np.float32)
    arm_nan = np.uint32([0x7FC00000]).view(np.float32)
    assert bitcompare.compare(x86_nan, arm_nan).ok
    result = bitcompare.compare(np.float32([[0.0, 1.0], [np.nan, 2.0]]), np.float32([[-0.0, 1.0], [3.0, 2.0]]))
    assert result.n_mismatches == 2 and list(result.mismatched_rows) == [0, 1]
    assert result.first[0].expected_bits == 0 and result.first[0].actual_bits == 0x80000000
    assert "0x00000000" in result.report()[1] and "0x80000000" in result.report()[1]


# ----------------------------------------------------------------------------- x86 build

SMALL_SOURCES = {"tiny.h": "float tiny_twice(float x);\n",
                 "tiny.c": '#include "tiny.h"\nfloat tiny_twice(float x) { return x + x; }\n'}
SMALL_CDEF = "float tiny_twice(float x);"
SMALL_HARNESS = '#include "tiny.h"'


def test_x86_build_is_cached_by_content(monkeypatch, tmp_path):
    monkeypatch.setenv("STAREGEN_CACHE", str(tmp_path))
    first = x86.build(SMALL_SOURCES, SMALL_CDEF, SMALL_HARNESS)
    assert first.lib.tiny_twice(1.5) == 3.0
    assert first.folder.parent == tmp_path / "x86" and first.folder.name == first.key
    changed = dict(SMALL_SOURCES, **{"tiny.c": SMALL_SOURCES["tiny.c"] + "\n"})
    assert x86.build_key(changed, SMALL_CDEF, SMALL_HARNESS) != first.key
    assert [p.name for p in (tmp_path / "x86").iterdir()] == [first.key]  # no temporaries left


def test_x86_concurrent_builds_of_one_key_are_safe(tmp_path):
    script = textwrap.dedent(f"""
        from firmware import x86
        b = x86.build({SMALL_SOURCES!r}, {SMALL_CDEF!r}, {SMALL_HARNESS!r})
        assert b.lib.tiny_twice(2.0) == 4.0
        print(b.key)
    """)
    env = dict(os.environ, STAREGEN_CACHE=str(tmp_path / "cache"), PYTHONPATH=os.getcwd())
    procs = [subprocess.Popen([sys.executable, "-c", script], env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                              text=True) for _ in range(2)]
    results = [p.communicate(timeout=120) + (p.returncode,) for p in procs]
    assert all(code == 0 for _, _, code in results), [err for _, err, _ in results]
    keys = {out.strip() for out, _, _ in results}
    assert len(keys) == 1 and [p.name for p in (tmp_path / "cache" / "x86").iterdir()] == [keys.pop()]


def test_x86_compile_error_and_missing_compiler_are_one_line_firmware_errors(monkeypatch, tmp_path):
    monkeypatch.setenv("STAREGEN_CACHE", str(tmp_path))
    broken = {"tiny.h": SMALL_SOURCES["tiny.h"], "tiny.c": "float tiny_twice(float x) { return x + 1.0; }\n"}
    with pytest.raises(FirmwareError) as info:
        x86.build(broken, SMALL_CDEF, SMALL_HARNESS)  # -Wdouble-promotion -Werror
    assert "tiny.c does not compile" in str(info.value) and "\n" not in str(info.value)
    with pytest.raises(FirmwareError, match="not found"):
        x86.build(SMALL_SOURCES, SMALL_CDEF, SMALL_HARNESS, cc="no-such-cc-staregen")


# ----------------------------------------------------------------------------- CLI

def run_cli(monkeypatch, capsys, *argv):
    monkeypatch.setattr(cli, "COMMANDS", ["host.cli.c_eval", "host.cli.verify"])
    code = cli.main([str(a) for a in argv])
    out, err = capsys.readouterr()
    return code, out, err


def test_cli_c_eval_golden_and_x86_agree(monkeypatch, capsys, tmp_path, net5):
    a, _ = net5
    path = a.save(tmp_path / "a.json")
    np.save(tmp_path / "in.npy", vectors.gate_vectors(a.envelope, 3_000, 2).x)
    outs = {}
    for target in ("golden", "x86"):
        code, _, err = run_cli(monkeypatch, capsys, "c-eval", "--artifact", path, "--target", target,
                               "--inputs", tmp_path / "in.npy", "--out", tmp_path / f"{target}.npy")
        assert code == 0, err
        outs[target] = np.load(tmp_path / f"{target}.npy")
    assert outs["x86"].dtype == np.float32 and outs["x86"].shape == (3_000, 2)
    assert_bits_equal(outs["golden"], outs["x86"])


@pytest.mark.parametrize("array, needle", [
    (np.zeros((4, 5), np.float64), "expected a float32 array of shape (N, 5), got float64"),
    (np.zeros((4, 6), np.float32), "got float32 (4, 6)"),
    (None, "no such file"),
])
def test_cli_c_eval_bad_inputs_one_line_error(monkeypatch, capsys, tmp_path, net5, array, needle):
    path = net5[0].save(tmp_path / "a.json")
    if array is not None:
        np.save(tmp_path / "in.npy", array)
    code, _, err = run_cli(monkeypatch, capsys, "c-eval", "--artifact", path, "--target", "golden",
                           "--inputs", tmp_path / "in.npy", "--out", tmp_path / "out.npy")
    assert code == 2 and len(err.strip().splitlines()) == 1 and needle in err
    assert not (tmp_path / "out.npy").exists()


def test_cli_verify_passes_and_reports(monkeypatch, capsys, tmp_path, net12):
    path = net12[0].save(tmp_path / "a.json")
    code, out, _ = run_cli(monkeypatch, capsys, "verify", "--artifact", path, "--target", "x86",
                           "--vectors", 5_000, "--seed", 4)
    assert code == 0
    assert "x86 vs golden: 0 mismatches in 15000 values" in out
    assert "golden vs float64 reference" in out and "PASS" in out and "total" in out


def test_cli_verify_exits_non_zero_on_a_mismatch(monkeypatch, capsys, tmp_path, net12):
    a = net12[0]

    def flipped(artifact):
        def evaluate(x):
            y = golden.network_eval(artifact, x)
            y.view(np.uint32)[10, 1] ^= 1  # one bit of one output
            return y
        return evaluate

    monkeypatch.setitem(c_eval.EVALUATORS, "x86", flipped)
    code, out, _ = run_cli(monkeypatch, capsys, "verify", "--artifact", a.save(tmp_path / "a.json"),
                           "--target", "x86", "--vectors", 1_000)
    assert code == 1 and "1 mismatches" in out and "row 10 col 1" in out and "FAIL" in out


def test_cli_verify_rejects_a_bad_vector_count(monkeypatch, capsys, tmp_path, net5):
    code, _, err = run_cli(monkeypatch, capsys, "verify", "--artifact", net5[0].save(tmp_path / "a.json"),
                           "--target", "x86", "--vectors", 0)
    assert code == 2 and len(err.strip().splitlines()) == 1 and "--vectors" in err
