"""The tanh-law unit (paper 000): closed-loop sequences with the state carried in the C, the gate's
coverage of every branch, other parameters and periods, the golden twin against the float64 host
law, the generated text (SPEC section 5) and parameter-file errors through the CLI. (What every
unit must do — gate on every class, a one-ulp change caught, SPEC 6 golden, determinism — is in
tests/codegen/units/test_every_unit.py.)"""
import json
import math
import re
from pathlib import Path

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

import host.cli as cli
from codegen.units.tanh import emit as tanh_emit
from codegen.units.tanh import golden as gt
from codegen.units.tanh.emit import INPUT_DTYPE, STATE_DTYPE
from codegen.units.tanh.params import TanhParamsError, load_params
from codegen.units.tanh.powtab import pow_tables
from codegen.units.tanh.unit import TanhUnit
from host.sim import tanh_example as ex
from host.control import tanh_law
from host.sim.scenarios import Paper000ClosedLoop
from tools.gate import compare_fields
from tools.runners import runner

PARAMS = ex.paper_parameters()
K = tanh_emit.constants32(PARAMS, 0.1)
ROOT = Path(__file__).resolve().parents[4]


@pytest.fixture(scope="module")
def unit():
    return TanhUnit(PARAMS, 0.1, Paper000ClosedLoop())


@pytest.fixture(scope="module")
def vectors(unit):
    return unit.gate_classes(14_000, seed=7)


@pytest.fixture(scope="module")
def sequences(unit):
    inputs = unit.gate_sequences(3, 1000, seed=7)
    return inputs, unit.golden_sequences(inputs)


def flat(records: np.ndarray) -> np.ndarray:
    """Structured records as float32 columns (status bits viewed as float)."""
    return np.ascontiguousarray(records).view(np.float32).reshape(records.shape + (-1,))


# ----------------------------------------------------------------------------- the closed loop


@pytest.mark.parametrize("target", ["x86", "arm"])
def test_closed_sequences_state_carried_in_c(unit, sequences, target):
    inputs, golden = sequences
    run = runner(unit, target)
    for s in range(inputs.shape[0]):
        run.reset()
        assert compare_fields(golden[s], run.sequence(inputs[s])) == []


def test_closed_sequences_converge_and_visit_the_fallback(sequences):
    inputs, golden = sequences
    status = golden["status"]
    assert (status == gt.STATUS_SINGULAR).any() and (status == gt.STATUS_OK).any()
    assert not (status == gt.STATUS_INVALID_INPUT).any()
    assert np.all(np.abs(golden["torque"]) <= 4.5)
    assert np.all(np.linalg.norm(golden["x1"][:, -1], axis=1) < 1e-2)  # converged after 100 s


def test_gate_vectors_cover_every_branch(vectors):
    state = np.concatenate([b.state for b in vectors.values()])
    inp = np.concatenate([b.input for b in vectors.values()])
    x = flat(inp)
    out, _ = gt.step(K, state, inp)
    status = out["status"]
    state = state["varpi"]
    counts = np.bincount(status, minlength=3)
    assert np.all(counts >= 500), counts
    ok = status == gt.STATUS_OK
    delta = (out["x2"][ok].astype(np.float64) - state[ok])
    dsq = np.sum(delta ** 2, axis=1)
    assert (dsq <= PARAMS.n1 ** 2).sum() >= 200 and (dsq > PARAMS.n1 ** 2).sum() >= 200          # u_a branches
    assert (dsq <= PARAMS.delta_reg).sum() >= 200 and (dsq > PARAMS.delta_reg).sum() >= 200      # ρ branches
    x1 = np.abs(out["x1"][ok])
    assert (x1 <= PARAMS.eta).sum() >= 200 and (x1 > PARAMS.eta).sum() >= 200                    # f branches
    assert (np.abs(out["varpi"]) == np.float32(PARAMS.varpi_limit)).any()                        # ϖ clamp
    reset = ~np.all(np.isfinite(state), axis=1)
    assert reset.sum() >= 50 and np.all(out["varpi"][reset] == 0) and np.all(status[reset] == 2)  # state reset
    # the validity test is a finite float32 sum of R_e, w_e, wdot_t: rows whose x1/x2 could overflow are
    # invalid (zeroed), so no output is ever NaN, even for the overflow and special classes
    assert not np.isnan(flat(out)).any()
    assert (status[np.all(np.isfinite(state), axis=1) & np.all(np.isfinite(x), axis=1)] == 2).sum() >= 50


def test_gate_other_parameters_and_period():
    """Nothing is specific to the paper's numbers: γ, η, n1, J and the period all move."""
    data = PARAMS.to_mapping()
    data.update(gamma=0.55, eta=0.02, n1=0.05, k4=3.0, inertia=[[3.0, 0.1, 0.0], [0.1, 2.0, -0.2], [0.0, -0.2, 4.0]])
    params = tanh_law.params_from_mapping(data)
    other = TanhUnit(params, 0.05)
    vectors = other.gate_classes(3_500, seed=1)
    for target in ("x86", "arm"):
        run = runner(other, target)
        for b in vectors.values():
            g_out, g_state = other.golden(b.state, b.input)
            out, state = run.records(b)
            assert compare_fields(g_out, out) == [] and compare_fields(g_state, state) == []


def test_old_gate_command_still_passes_with_a_deprecation_line(capsys):
    code = cli.main(["tanh", "gate", "--params", str(ROOT / "docs/tanh_paper000.toml"), "--vectors", "700",
                     "--sequences", "1", "--steps", "50"])
    res = capsys.readouterr()
    assert code == 0, res.out
    assert "PASS" in res.out and "arm vs golden" in res.out and "deprecated" in res.out and res.err == ""


# ----------------------------------------------------------------------------- golden vs float64


def test_golden_matches_the_float64_law():
    """Away from the ρ switch (δᵀδ within 5 % of delta_reg) and 180°, float32 vs float64:
    torque within 2e-3 N·m (tanh(50·) amplifies rounding ×75), the new ϖ within 1e-4 + 1e-3|ϖ|."""
    rng = np.random.default_rng(3)
    n = 3000
    R_t = Rotation.random(n, random_state=rng).as_matrix()
    # errors up to 115°: nearer 180° x1 = vee(R_e − R_eᵀ)/(2s) loses ~1e-7/q0² to the cancellation in
    # s² = 1 + tr R_e (float32), which is the float32 resolution of the input, not an error of the C
    rotvec = rng.normal(size=(n, 3))
    rotvec *= (rng.uniform(0.0, 2.0, n) / np.linalg.norm(rotvec, axis=1))[:, None]
    R_c = R_t @ Rotation.from_rotvec(rotvec).as_matrix()
    w_c, w_t, wdot_t = rng.normal(scale=0.2, size=(n, 3)), rng.normal(scale=0.01, size=(n, 3)), np.zeros((n, 3))
    varpi = rng.normal(scale=1.0, size=(n, 3)).astype(np.float32)
    x = np.concatenate([R_c.reshape(n, 9), w_c, R_t.reshape(n, 9), w_t, wdot_t], axis=1).astype(np.float32)
    out, new_state = gt.step(K, varpi.view(STATE_DTYPE).reshape(n), x.view(INPUT_DTYPE).reshape(n))
    new_state, out = new_state["varpi"], flat(out)
    C = tanh_law.compile_constants(PARAMS)
    checked = 0
    for i in range(n):
        r = x[i].astype(float)
        law = tanh_law.evaluate_law(C, tuple(varpi[i].astype(float)), tanh_law._as_mat(r[0:9].reshape(3, 3)),
                                    tuple(r[9:12]), tanh_law._as_mat(r[12:21].reshape(3, 3)), tuple(r[21:24]),
                                    tuple(r[24:27]))
        dsq = sum((a - b) ** 2 for a, b in zip(law.x2, varpi[i].astype(float)))
        if law.status != 0 or abs(dsq - PARAMS.delta_reg) < 0.05 * PARAMS.delta_reg:
            continue
        checked += 1
        assert out[i, 12].view(np.uint32) == 0
        np.testing.assert_allclose(out[i, 0:3], law.torque, atol=2e-3)
        np.testing.assert_allclose(out[i, 3:6], law.x1, atol=1e-6)
        v64 = tanh_law.euler_update(tuple(varpi[i].astype(float)), law.varpi_dot, 0.1, PARAMS.varpi_limit)
        np.testing.assert_allclose(new_state[i], v64, atol=1e-4, rtol=1e-3)
    assert checked > 0.9 * n


# ----------------------------------------------------------------------------- generated text


def test_generation_is_deterministic_and_documented():
    a, b = tanh_emit.tanh_sources(PARAMS), tanh_emit.tanh_sources(ex.paper_parameters())
    assert a == b and set(a) == {"tanh.h", "tanh.c", "sg_math.h", "sg_math.c"}
    h, c = a["tanh.h"], a["tanh.c"]
    sha = tanh_emit.params_sha256(PARAMS, 0.1)
    assert sha in h and sha in c and tanh_emit.GENERATOR_VERSION in h
    for needle in ("void tanh_init(tanh_state_t *state);", "tanh_input_t", "tanh_output_t", "N*m", "rad/s",
                   "row-major", "TANH_STATUS_SINGULAR", "TANH_STATUS_INVALID_INPUT"):
        assert needle in h
    other = tanh_emit.tanh_sources(PARAMS, period=0.05)
    assert other["tanh.c"] != c and "#define TANH_T (0x1.99999ap-5f)" in other["tanh.c"]


def test_generated_c_follows_spec_5():
    c = tanh_emit.tanh_sources(PARAMS)["tanh.c"]
    code = re.sub(r"/\*.*?\*/", "", c, flags=re.S)
    assert "double" not in code and "malloc" not in code and "<math.h>" not in code
    assert not re.search(r"\b(tanhf?|expf?|logf?|powf?|sqrtf?)\s*\(", code)
    # every floating literal is a hex float or carries the f suffix
    for lit in re.findall(r"(?<![\w.])(\d+\.\d*(?:e[+-]?\d+)?f?|0x[0-9a-f.]+p[+-]?\d+f?)", code, flags=re.I):
        assert lit.lower().endswith("f"), lit
    # constants round-trip exactly: the literal is the float32 of constants32
    assert f"#define TANH_K4 ({tanh_emit.c_float(K.k4)})" in code
    # mutable state only through the caller's struct: file-scope objects are const
    for line in code.splitlines():
        if line.startswith("static") and "=" in line and "(" not in line.split("=")[0]:
            assert "const" in line, line


def test_golden_refuses_flat_rows():
    with pytest.raises(ValueError, match="records"):
        gt.step(K, np.zeros((1, 3), np.float32), np.zeros((1, 27), np.float32))


def test_paper_parameter_file_is_the_example():
    assert load_params(ROOT / "docs/tanh_paper000.toml") == PARAMS


# ----------------------------------------------------------------------------- parameter-file errors


@pytest.mark.parametrize("edit, message", [
    (lambda d: d.pop("k4"), "missing key 'k4'"),
    (lambda d: d.update(k2=-1.5), "'k2' = -1.5 must be > 0"),
    (lambda d: d.update(gamma=1.0), "'gamma' = 1.0 must be in (0, 1)"),
    (lambda d: d.update(gamma=-0.2), "'gamma' = -0.2 must be in (0, 1)"),
])
@pytest.mark.parametrize("command", [["codegen", "--unit", "tanh", "--out", "{out}"], ["cycles", "--unit", "tanh"],
                                     ["verify", "--unit", "tanh"], ["tanh", "gate"]])
def test_parameter_errors_are_one_line_through_the_cli(tmp_path, capsys, edit, message, command):
    data = PARAMS.to_mapping()
    edit(data)
    path = tmp_path / "p.json"
    path.write_text(json.dumps(data))
    argv = [a.replace("{out}", str(tmp_path / "gen")) for a in command] + ["--params", str(path)]
    code = cli.main(argv)
    res = capsys.readouterr()
    deprecation = "staregen: 'tanh gate' is deprecated and will be removed; use 'verify --unit tanh'\n"
    assert code == 2 and res.out == (deprecation if command[0] == "tanh" else "")
    assert res.err == f"staregen {command[0]}: error: {path}: {message}\n"
    assert not (tmp_path / "gen").exists()


def test_params_error_class_is_a_codegen_error():
    from codegen.errors import CodegenError

    assert issubclass(TanhParamsError, CodegenError)
    with pytest.raises(CodegenError, match="control period"):
        tanh_emit.constants32(PARAMS, -0.1)
    assert math.isclose(float(K.period), 0.1, rel_tol=1e-7)


@pytest.mark.parametrize("n1", [0.05, 0.1, 1e-3, 0.3, 2.0, 1e-20, 1.9e19, 3e38])
def test_n1_dsq_threshold_matches_the_sqrt_branch(n1):
    """The generated N1_DSQ: sqrtf(d) > n1 <=> d > N1_DSQ for every float32 d (checked at the
    threshold's neighbours and on random bit patterns), so u_a's branch needs no VSQRT inside n1."""
    from codegen.units.tanh.emit import sqrt_gt_threshold
    n = np.float32(n1)
    t = sqrt_gt_threshold(n)
    assert np.sqrt(t) <= n
    assert t == np.finfo(np.float32).max or np.sqrt(np.nextafter(t, np.float32(np.inf))) > n
    rng = np.random.default_rng(7)
    d = np.concatenate([rng.integers(0, 0x7F800000, 100_000, dtype=np.uint64).astype(np.uint32).view(np.float32),
                        (t.view(np.uint32) + np.arange(-50, 51, dtype=np.int64)).clip(0, 0x7F7FFFFF).astype(np.uint32)
                        .view(np.float32), np.float32([np.inf, np.nan, 0.0])])
    with np.errstate(invalid="ignore"):
        assert np.array_equal(np.sqrt(d) > n, d > t)


def test_power_tables_are_within_2_5_ulp():
    """powtab's K x^y (the C's <name>_pow_*3, twin golden.pow_scaled) against float64: ≤ 2.5 ulp for
    normal x of both signs over the whole range, ±0 for ±0 and subnormal x, finite for Inf/NaN."""
    rng = np.random.default_rng(11)
    for y, scale in ((float(K.gamma_m1), float(K.beta2)), (float(K.gamma), float(K.ua_inner)), (-0.95, 1.0),
                     (0.05, 1.0), (0.95, 0.5)):
        t = pow_tables(y, scale)
        x = (10.0 ** rng.uniform(-37.9, 38.0, 100_000)).astype(np.float32)
        x = np.concatenate([x, -x])
        with np.errstate(all="ignore"):
            got = gt.pow_scaled(x, t).astype(np.float64)
        y32, k32 = float(np.float32(y)), float(np.float32(scale))
        ref = np.sign(x.astype(np.float64)) * k32 * np.abs(x.astype(np.float64)) ** y32
        normal = np.abs(ref) > np.finfo(np.float32).tiny
        ulp = np.spacing(np.abs(ref).astype(np.float32)).astype(np.float64)
        assert (np.abs(got - ref) / ulp)[normal].max() <= 2.5, (y, scale)
        special = np.array([0.0, -0.0, 1e-40, -1e-40, np.inf, -np.inf, np.nan], dtype=np.float32)
        with np.errstate(all="ignore"):
            out = gt.pow_scaled(special, t)
        assert np.all(out[:4] == 0.0) and np.all(np.isfinite(out))
