"""Bit-exact gate: golden model == x86 C on uint32 bit patterns; the gate's own sensitivity;
vector coverage; golden vs float64 reference bound; x86 build cache; c-eval / verify CLI."""
import inspect

import numpy as np
import pytest

import host.cli as cli
import tools.gate
from codegen import artifact as art
from codegen import bitcompare
from codegen.units.network import fold, golden, reference, vectors
from codegen.units.network.unit import NetworkUnit
from tools.runners import X86Runner

GATE_VECTORS = 20_000
# Golden vs the float64 reference of the same network, in-envelope inputs: |error| <= this
# fraction of the output data range (measured ~2.5e-7 for random 12-40-3 artifacts).
REFERENCE_BOUND = 1e-6


class X86Network:
    """The network unit's x86 build on float32 rows (N, n): the path and each stage."""

    def __init__(self, a):
        self.run = X86Runner(NetworkUnit(a))

    def _stage(self, name, x):
        rec = np.zeros(x.shape[0], dtype=self.run.unit.stages[name].input)
        rec["x"] = x
        return np.ascontiguousarray(self.run.stage(name, rec)["y"])

    def eval(self, x):
        rec = np.zeros(x.shape[0], dtype=self.run.unit.input_dtype)
        rec["x"] = x
        return np.ascontiguousarray(self.run.sequence(rec)["y"])

    def normalise(self, x):
        return self._stage("normalise", x)

    def mlp(self, x):
        return self._stage("mlp", x)

    def denormalise(self, x):
        return self._stage("denormalise", x)


@pytest.fixture(scope="module")
def net12():
    a = art.random_artifact((12, 40, 3), seed=1)
    return a, X86Network(a)


@pytest.fixture(scope="module")
def net5():
    a = art.random_artifact((5, 17, 2), seed=1)
    return a, X86Network(a)


def assert_bits_equal(expected, actual, inner_stage: bool = False):
    """uint32 equality everywhere, NaN included (the network's outputs are canonical NaNs). An inner
    stage's result (normalise, mlp) is not an output: its NaNs are not canonicalised, so there any
    NaN equals any NaN."""
    e, a = expected.view(np.uint32), actual.view(np.uint32)
    bad = e != a
    if inner_stage:
        bad &= ~(np.isnan(expected) & np.isnan(actual))
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
    assert_bits_equal(xn, lib.normalise(x), inner_stage=True)
    yn = golden.mlp(a, xn)
    assert_bits_equal(yn, lib.mlp(xn), inner_stage=True)
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
    f = fold.fold(a)
    xn = golden.normalise(a, vectors.gate_vectors(a.envelope, 2_000, 0).x)
    acc = np.zeros((xn.shape[0], a.n_hidden), np.float32)
    with np.errstate(all="ignore"):  # the vectors include Inf/NaN rows
        for i in range(a.n_in):
            acc = acc + f.W1[:, i] * xn[:, i, None]
    in_order = golden.output_layer(a, golden.tansig(golden.hidden_preactivation(a, xn)))
    assert_bits_equal(in_order, lib.mlp(xn), inner_stage=True)  # the same, bias first: identical
    reordered = golden.output_layer(a, golden.tansig(acc + f.b1))
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
    for fn in (golden.normalise, golden._normalise, golden.hidden_preactivation, golden._hidden_preactivation,
               golden.tansig, golden.output_layer, golden._output_layer, golden._mlp, golden.mlp,
               golden.denormalise, golden._canonical, golden.network_eval):
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
    assert "x86 vs golden" in out and "identical" in out and "inside 3250" in out
    assert "golden vs float64 reference" in out and "PASS" in out and "total" in out


def test_cli_verify_exits_non_zero_on_a_mismatch(monkeypatch, capsys, tmp_path, net12):
    a = net12[0]
    real = tools.gate.runner

    class Flipped:
        """The real x86 runner with one bit of one output flipped."""

        def __init__(self, unit, target):
            self.inner = real(unit, target)

        def records(self, batch):
            out, state = self.inner.records(batch)
            out["y"].view(np.uint32)[10, 1] ^= 1
            return out, state

    monkeypatch.setattr(tools.gate, "runner", Flipped)
    code, out, _ = run_cli(monkeypatch, capsys, "verify", "--artifact", a.save(tmp_path / "a.json"),
                           "--target", "x86", "--vectors", 1_000)
    assert code == 1 and "1 mismatches" in out and "row 10 col 1" in out and "FAIL" in out


def test_cli_verify_rejects_a_bad_vector_count(monkeypatch, capsys, tmp_path, net5):
    code, _, err = run_cli(monkeypatch, capsys, "verify", "--artifact", net5[0].save(tmp_path / "a.json"),
                           "--target", "x86", "--vectors", 0)
    assert code == 2 and len(err.strip().splitlines()) == 1 and "--vectors" in err


def test_cli_verify_with_fewer_vectors_than_classes(monkeypatch, capsys, tmp_path, net5):
    """Two vectors leave three classes empty: they are skipped, the gate still runs and passes."""
    code, out, _ = run_cli(monkeypatch, capsys, "verify", "--artifact", net5[0].save(tmp_path / "a.json"),
                           "--target", "x86", "--vectors", 2)
    assert code == 0 and "vectors: 2 (inside 2)" in out and "PASS" in out
