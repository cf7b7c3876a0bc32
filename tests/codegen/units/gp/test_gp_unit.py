"""Unit gp (paper 004's sparse-GP takeover law): the golden step against an independent float64 GP and
law, the clamps, the invalid path, the parameter file and the emitter's refusals. The bit-exact gate
(golden == x86 == ARM) is tests/codegen/units/test_every_unit.py's."""
from __future__ import annotations

import json
import shutil
import subprocess
from pathlib import Path

import numpy as np
import pytest
from scipy.linalg import cholesky, solve_triangular

from codegen.errors import CodegenError
from codegen.units.gp import artifact as gpa
from codegen.units.gp import golden, records
from codegen.units.gp.emit import W_MAX, check_magnitudes, constants32, gp_sources, schedule_scale
from codegen.units.gp.example import example_artifact, example_params
from codegen.units.gp.params import GpLawParams, GpParamsError, load_params
from codegen.units.gp.unit import GpUnit, configure
from firmware.flags import COMMON
from tools.gate import run_gate
from tools.runners import X86Runner

F32 = np.float32
DOCS = Path(__file__).resolve().parents[4] / "docs"


@pytest.fixture(scope="module")
def unit():
    return GpUnit(example_params(m=12, seed=3))


def rows(q, omega, h_w) -> np.ndarray:
    x = np.concatenate([np.atleast_2d(q), np.atleast_2d(omega), np.atleast_2d(h_w)], axis=1).astype(F32)
    return np.ascontiguousarray(x).view(records.INPUT_DTYPE).reshape(len(x))


def float64_gp(a: gpa.GpArrays, x6: np.ndarray):
    """Mean and variance of the SVGP at [q_v, omega, 0], written from the formulas (Cholesky of K_ZZ,
    triangular solves), not from the artifact module."""
    x = np.concatenate([x6, np.zeros((len(x6), 3))], axis=1) / a.input_scale
    z = a.Z
    d2 = (((x[:, None, :] - z[None, :, :]) / a.lengthscale) ** 2).sum(-1)
    kx = a.outputscale * np.exp(-0.5 * d2)
    dz = (((z[:, None, :] - z[None, :, :]) / a.lengthscale) ** 2).sum(-1)
    L = cholesky(a.outputscale * np.exp(-0.5 * dz) + a.jitter * np.eye(len(z)), lower=True)
    w = solve_triangular(L, kx.T, lower=True)
    mean = np.stack([a.m[k] @ w for k in range(3)], axis=1) * a.output_scale
    var = np.stack([a.outputscale - (w * w).sum(0) + ((a.R[k].T @ w) ** 2).sum(0) for k in range(3)], axis=1)
    return mean, var * a.output_scale ** 2


def float64_residual(a: gpa.GpArrays, x6: np.ndarray) -> np.ndarray:
    """k_xx - |L^-1 k_Zx|^2 in float64 (normalised units), from the formulas."""
    x = np.concatenate([x6, np.zeros((len(x6), 3))], axis=1) / a.input_scale
    kx = a.outputscale * np.exp(-0.5 * (((x[:, None, :] - a.Z[None, :, :]) / a.lengthscale) ** 2).sum(-1))
    dz = (((a.Z[:, None, :] - a.Z[None, :, :]) / a.lengthscale) ** 2).sum(-1)
    L = cholesky(a.outputscale * np.exp(-0.5 * dz) + a.jitter * np.eye(len(a.Z)), lower=True)
    w = solve_triangular(L, kx.T, lower=True)
    return a.outputscale - (w * w).sum(0)


def test_golden_agrees_with_an_independent_float64_gp_inside_the_data(unit):
    a = unit.params.gp.arrays
    batch = unit.gate_classes(3000, 5)["inside"].input
    out, state = unit.golden(None, batch)
    assert state is None
    q = batch["q"].astype(np.float64)
    q /= np.linalg.norm(q, axis=1, keepdims=True)
    q_v = np.where(q[:, 3:] < 0, -q[:, :3], q[:, :3])
    mean, var = float64_gp(a, np.concatenate([q_v, batch["omega"].astype(np.float64)], axis=1))
    prior = a.output_scale ** 2 * a.outputscale
    assert np.abs(out["mu"] - mean).max() <= 1e-5 * a.output_scale.max() * np.abs(a.m).sum()
    expected = np.clip(var, 0.0, prior)                  # the flight clamps to [0, prior]
    assert np.abs(out["var"] - expected).max() <= 1e-5 * prior.max()
    assert (var > prior).any()                           # the example's third axis has an S eigenvalue above 1


def test_torque_is_the_law_of_section_5(unit):
    p = unit.params
    classes = unit.gate_classes(3000, 6)
    batch = np.concatenate([classes["inside"].input, classes["edges"].input])
    out, _ = unit.golden(None, batch)
    q = batch["q"].astype(np.float64)
    q /= np.linalg.norm(q, axis=1, keepdims=True)
    q_v = np.where(q[:, 3:] < 0, -q[:, :3], q[:, :3])
    w = batch["omega"].astype(np.float64)
    J = np.array(p.inertia)
    K1, K2 = out["gains"][:, :1].astype(np.float64), out["gains"][:, 1:].astype(np.float64)
    tau = -K1 * q_v - K2 * w + np.cross(w, w @ J.T + batch["h_w"]) - out["mu"]
    free = (out["status"] & records.STATUS_TORQUE_LIMITED) == 0
    assert free.sum() > 300 and (~free).sum() > 20
    assert np.abs(out["torque"][free] - tau[free]).max() <= 1e-5
    assert np.all(np.abs(out["torque"][~free]) <= p.torque_max)
    assert np.all(np.sign(out["torque"][~free]) == np.sign(np.clip(tau[~free], -p.torque_max, p.torque_max)))


def test_gains_rise_with_the_variance_between_their_bounds(unit):
    p = unit.params
    out = np.concatenate([unit.golden(None, b.input)[0] for b in unit.gate_classes(6000, 7).values()])
    s = (out["var"] / constants32(p).prior_var).max(axis=1)
    order = np.argsort(s, kind="stable")
    k1, k2 = out["gains"][order, 0], out["gains"][order, 1]
    assert np.all(np.diff(k1) >= -2e-6 * p.k1_bar) and np.all(np.diff(k2) >= -2e-6 * p.k2_bar)
    assert k1.min() >= p.k1 and k1.max() <= p.k1_bar and k2.min() >= p.k2 and k2.max() <= p.k2_bar
    assert np.isclose(k1.min(), p.k1 + (p.k1_bar - p.k1) * s.min(), rtol=1e-5)


def test_far_from_the_data_the_variance_is_the_prior_and_the_mean_vanishes(unit):
    c = unit.constants
    out, _ = unit.golden(None, unit.gate_classes(600, 8)["far"].input)
    assert np.array_equal(out["var"].view(np.uint32), np.broadcast_to(c.prior_var, out["var"].shape).view(np.uint32))
    assert np.abs(out["mu"]).max() < 1e-30
    assert np.all(out["gains"] == np.array([c.k1_bar, c.k2_bar], dtype=F32))


def test_the_floor_acts_only_where_the_true_residual_vanishes_and_the_variance_never_turns_negative(unit):
    """At the inducing points (the example has no jitter and omega_dot = 0 there) the float64 Nystrom
    residual k_xx - |L^-1 k|^2 is 0 up to float64 rounding; float32 rounds it either way, and where the
    step floors it the float64 value is that tiny: the floor removes rounding, not information."""
    a = unit.params.gp.arrays
    batch = unit.gate_classes(6000, 9)["inducing"].input
    out, _ = unit.golden(None, batch)
    floored = (out["status"] & records.STATUS_VAR_FLOOR) != 0
    assert floored.sum() > 50
    q = batch["q"].astype(np.float64)
    q /= np.linalg.norm(q, axis=1, keepdims=True)
    x6 = np.concatenate([np.where(q[:, 3:] < 0, -q[:, :3], q[:, :3]), batch["omega"].astype(np.float64)], axis=1)
    residual = float64_residual(a, x6)
    assert np.abs(residual[floored]).max() <= 1e-5 * a.outputscale
    assert not np.any(out["var"].view(np.uint32) >> np.uint32(31))
    # the floored variance is the variational part alone: the float64 value without the residual
    _, var = float64_gp(a, x6)
    expected = np.minimum(var - residual[:, None] * a.output_scale ** 2, a.output_scale ** 2 * a.outputscale)
    assert np.abs(out["var"][floored] - expected[floored]).max() <= 1e-5 * (a.output_scale ** 2 * a.outputscale).max()


def test_invalid_inputs_fly_nothing_and_report_the_prior():
    u = GpUnit(example_params())
    c = u.constants
    ok = rows([0.0, 0.0, 0.0, 1.0], [0.0, 0.0, 0.0], [0.0, 0.0, 0.0])
    bad = np.concatenate([ok] * 6)
    bad["q"][0, 1] = np.nan
    bad["omega"][1, 2] = np.nextafter(F32(records.RATE_MAX), F32(1))
    bad["h_w"][2, 0] = -np.inf
    bad["q"][3] = [0.0, 0.0, 0.0, 0.899]                 # |q|^2 = 0.808 < 0.81
    bad["q"][4] = [0.0, 0.0, 0.0, 1.1]                   # |q|^2 = 1.21 (inside) ...
    bad["q"][5] = [0.0, 0.0, 0.0, np.nextafter(F32(1.1), F32(2))]   # ... one step beyond |q_i| <= 1.1
    out, _ = u.golden(None, bad)
    invalid = out["status"] == records.STATUS_INVALID_INPUT
    assert invalid.tolist() == [True, True, True, True, False, True]
    assert np.all(out["torque"][invalid] == 0) and np.all(out["mu"][invalid] == 0)
    assert np.all(out["var"][invalid] == c.prior_var) and np.all(out["gains"][invalid] == [c.k1_bar, c.k2_bar])


def test_the_c_agrees_on_hand_made_rows():
    """A few rows the classes do not make (identity attitude, q4 = -1, an inducing point) through x86."""
    u = GpUnit(example_params())
    a = u.params.gp.arrays
    z = a.Z[0, :6] * a.input_scale[:6]
    q4 = np.sqrt(1 - (z[:3] ** 2).sum())
    batch = np.concatenate([rows([0, 0, 0, 1], [0, 0, 0], [0, 0, 0]), rows([0, 0, 0, -1], [0, 0, 0], [1, 2, 3]),
                            rows([*z[:3], q4], z[3:], [10, -20, 30]), rows([*-z[:3], -q4], z[3:], [10, -20, 30])])
    expected, _ = u.golden(None, batch)
    got, _ = X86Runner(u).records(type(u.gate_classes(6, 0)["inside"])(None, batch))
    assert np.array_equal(got.view(np.uint32), expected.view(np.uint32))
    assert np.array_equal(expected["torque"][2].view(np.uint32), expected["torque"][3].view(np.uint32))  # same attitude


# ----------------------------------------------------------------------------- the parameter file

def write_law(tmp_path, text: str, artifact: gpa.GpArtifact | None = example_artifact()):
    if artifact is not None:
        artifact.save(tmp_path / "gp.json")
    path = tmp_path / "law.toml"
    path.write_text(text)
    return path


LAW = """artifact = "gp.json"
k1 = 4.0
k1_bar = 16.0
k2 = 72.0
k2_bar = 144.0
torque_max = 1.0
inertia = [[797.34, -14.3, -25.1], [-14.3, 304.86, -10.5], [-25.1, -10.5, 792.48]]
"""


def test_the_law_file_reads_its_artifact_relative_to_itself(tmp_path, monkeypatch):
    path = write_law(tmp_path, LAW)
    monkeypatch.chdir("/")
    p = load_params(path)
    assert p.gp.sha256 == example_artifact().sha256 and p.k2_bar == 144.0 and p.inertia[1][1] == 304.86
    assert configure(params=p).values_sha256() == p.sha256()
    changed = load_params(write_law(tmp_path, LAW.replace("k2_bar = 144.0", "k2_bar = 145.0"), None))
    assert changed.sha256() != p.sha256()


@pytest.mark.parametrize("edit, message", [
    (("k1 = 4.0\n", ""), "missing key 'k1'"),
    (("k1 = 4.0", "k1 = 4.0\nk3 = 1.0"), "unknown key 'k3'"),
    (('"gp.json"', '"nothere.json"'), "artifact: .*nothere.json"),
    (('"gp.json"', "3"), "artifact: must be a file name"),
    (('"gp.json"', '"g\\u0007p.json"'), "printable characters"),
    (("k1_bar = 16.0", "k1_bar = 3.0"), "k1_bar: must be >= k1"),
    (("k2 = 72.0", "k2 = -72.0"), "k2: must be in"),
    (("torque_max = 1.0", "torque_max = 1e3"), "torque_max: must be in"),
    (("[-14.3, 304.86", "[-14.0, 304.86"), "inertia: must be symmetric"),
    (("[[797.34", "[[-797.34"), "inertia: must be positive definite"),
    (("[-25.1, -10.5, 792.48]]", "[-25.1, -10.5]]"), r"inertia\[2\]: must be a row of 3"),
    (("k1 = 4.0", "k1 = 4_0.0"), "no '_'"),
    (('"gp.json"', '"/etc/gp.json"'), "must be relative to the law file's folder"),
    (('"gp.json"', '"../gp.json"'), "without '..'"),
    (('"gp.json"', '"gp\u2028.json"'), "printable characters"),
])
def test_a_bad_law_file_is_refused_in_one_line(tmp_path, edit, message):
    path = write_law(tmp_path, LAW.replace(*edit))
    with pytest.raises(GpParamsError, match=message) as exc:
        load_params(path)
    assert "\n" not in str(exc.value) and str(path) in str(exc.value)


def test_a_tampered_artifact_is_refused_through_the_law_file(tmp_path):
    path = write_law(tmp_path, LAW)
    art = tmp_path / "gp.json"
    art.write_text(art.read_text().replace('"jitter": "0x0p+0"', '"jitter": "0x1p-20"'))
    with pytest.raises(GpParamsError, match="gp.json: .*sha256|gp.json: payload"):
        load_params(path)


# ----------------------------------------------------------------------------- the emitter

@pytest.mark.parametrize("change, message", [
    (lambda fl: fl["A"].__setitem__(0, F32(2 * W_MAX)), "row sums of"),
    (lambda fl: fl["R"].__setitem__((1, 0), F32(1e30)), r"axis 1: \|R_k\^T w\|"),
    (lambda fl: fl["m"].__setitem__((2, 0), F32(1e36)), "axis 2: the mean's sum may reach"),
    # a tiny output scale keeps the scaled mean small, but the sum before scaling overflows
    (lambda fl: (fl["m"].__setitem__((0, 0), F32(3e37)), fl["mu_scale"].__setitem__(0, F32(1e-20))),
     "axis 0: the mean's sum may reach"),
])
def test_arrays_that_could_overflow_float32_are_refused(change, message):
    fl = {k: np.array(v, copy=True) for k, v in example_artifact().flight.items()}
    check_magnitudes(fl, 8)
    change(fl)
    with pytest.raises(CodegenError, match=message):
        check_magnitudes(fl, 8)


def test_one_inducing_point_is_refused():
    with pytest.raises(CodegenError, match="at least 2 inducing points"):
        constants32(GpLawParams(gp=example_artifact(m=1), inertia=example_params().inertia))


def test_the_schedule_never_exceeds_one():
    """1/k_xx is lowered by an ulp where fl(k_xx * f32(1/sigma_f^2)) rounds above 1 (about 5 % of values)."""
    rng = np.random.default_rng(4)
    nudged = 0
    for sf in rng.uniform(0.1, 10.0, 4000):
        kxx, inv = F32(sf), F32(1.0 / sf)
        s = schedule_scale(kxx, inv)
        assert kxx * s <= F32(1.0) and s <= inv and (s == inv or np.nextafter(s, F32(np.inf)) == inv)
        nudged += s != inv
    assert nudged > 40


def test_the_sources_name_the_artifact_and_bake_no_text_from_the_file():
    p = example_params()
    meta = dict(p.gp.metadata, creator="*/ evil(); /*")
    hostile = GpLawParams(gp=gpa.GpArtifact(p.gp.arrays, p.gp.envelope_min, p.gp.envelope_max, metadata=meta),
                          inertia=p.inertia, artifact_name="*/ x(); /*")
    c = gp_sources(hostile)["gp.c"] + gp_sources(hostile)["gp.h"]
    assert "evil" not in c and "x();" not in c and hostile.gp.sha256 in c


def test_the_trained_default_passes_the_gate_on_x86():
    """The committed M = 20 model (docs/gp_paper004.toml), not only the example, golden == x86."""
    unit = configure(params=load_params(DOCS / "gp_paper004.toml"))
    assert run_gate(unit, 3000, targets=("x86",), log=lambda line: None).ok


def test_a_loaded_artifact_is_the_file_bit_for_bit():
    """The C bakes in the file's float32 arrays and the file's seal, not a re-derivation on this machine."""
    path = DOCS / "gp_takeover_m20.json"
    g = gpa.load(path)
    assert g.to_json() == path.read_text() and g.sha256 == json.loads(path.read_text())["sha256"]
    assert g.recorded_flight is not None and g.recorded_conditioning is not None


@pytest.mark.parametrize("cc", ["gcc", "clang"])
def test_gcc_and_clang_compile_the_unit_with_the_flight_flags(tmp_path, cc):
    """SPEC section 5: the generated C builds with gcc and clang under -Werror (the trained M = 20 model)."""
    if shutil.which(cc) is None:
        pytest.fail(f"{cc} is not installed (make setup installs it)")
    for name, text in gp_sources(load_params(DOCS / "gp_paper004.toml")).items():
        (tmp_path / name).write_text(text)
    flags = [f for f in COMMON if cc == "gcc" or f != "-fexcess-precision=standard"]
    res = subprocess.run([cc, *flags, "-Wconversion", "-c", str(tmp_path / "gp.c"), "-o", str(tmp_path / "gp.o")],
                         capture_output=True, text=True)
    assert res.returncode == 0, res.stderr
