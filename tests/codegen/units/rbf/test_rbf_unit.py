"""The rbf unit (paper 002's RBF adaptive finite-time backstepping law, docs/rbf-backstepping.md
section 11): the golden twin against an independent float64 computation of the step written here
from the document (matrices, not the golden model's expanded formulas), the safety rules (invalid
rows leave the weights bit-identical and the command 0, every weight finite and within its column's
bound, a caller's corrupted state repaired), theorem 2's second network on the previous command,
theorem 1, a one-ulp change of a weight caught, and the CLI's one-line parameter errors. (What every unit must do — gate on x86 and ARM, a one-ulp change of a constant
caught, SPEC 6 golden, determinism — is tests/codegen/units/test_every_unit.py.)"""
from __future__ import annotations

import json
import shutil
import subprocess
from pathlib import Path

import numpy as np
import pytest

import host.cli as cli
from codegen.package.selftest import make_vectors, selftest_sources
from codegen.unit import Batch
from codegen.units.rbf import golden
from codegen.units.rbf import records as rec
from codegen.units.rbf.params import example_params, load_params, paper_params, params_from_mapping
from codegen.units.rbf.unit import RbfUnit
from firmware.flags import COMMON
from tools.fuzz import fuzz
from tools.gate import compare_fields
from tools.runners import runner

ROOT = Path(__file__).resolve().parents[4]
PAPER = load_params(ROOT / "docs/rbf_paper002.toml")
THEOREM1 = params_from_mapping({**PAPER.to_mapping(), "theorem": 1, "nodes": 6, "alpha": 0.75})

pytestmark = pytest.mark.usefixtures("private_cache")


@pytest.fixture(scope="module", params=["paper", "example", "theorem1"])
def unit(request):
    return RbfUnit({"paper": PAPER, "example": example_params(), "theorem1": THEOREM1}[request.param])


# ----------------------------------------------------------------------------- float64 reference


def _rx(a):
    c, s = np.cos(a), np.sin(a)
    return np.array([[1, 0, 0], [0, c, s], [0, -s, c]])


def _ry(a):
    c, s = np.cos(a), np.sin(a)
    return np.array([[c, 0, -s], [0, 1, 0], [s, 0, c]])


def _rz(a):
    c, s = np.cos(a), np.sin(a)
    return np.array([[c, s, 0], [-s, c, 0], [0, 0, 1]])


def _wrap(d):
    return d - 2 * np.pi if d > np.pi else (d + 2 * np.pi if d < -np.pi else d)


def reference_step(p, period: float, theta: np.ndarray, theta_d: np.ndarray, command: np.ndarray, x: np.void):
    """Section 11 in float64 for one valid row whose command is in [-1, 1]: (force, torque, w_hat, theta after,
    theta_delta after, command after)."""
    g = {name: np.asarray(x[name], dtype=np.float64) for name in rec.INPUT_DTYPE.names}
    rho, qe, qb = g["los"]
    phi, th, psi = g["euler"]
    om = g["omega"]
    a, k1, k2, J = p.alpha, np.array(p.k1), np.array(p.k2), np.array(p.inertia)
    R = np.array([[np.cos(th), 0, -np.sin(th) * np.cos(phi)], [0, 1, np.sin(phi)],
                  [np.sin(th), 0, np.cos(th) * np.cos(phi)]])
    Rinv = np.linalg.inv(R)
    eul_rate = Rinv @ om                                    # (phi', theta', psi')
    dR_dphi = np.array([[0, 0, np.sin(th) * np.sin(phi)], [0, 0, np.cos(phi)], [0, 0, -np.cos(th) * np.sin(phi)]])
    dR_dth = np.array([[-np.sin(th), 0, -np.cos(th) * np.cos(phi)], [0, 0, 0], [np.cos(th), 0, -np.sin(th) * np.cos(phi)]])
    Rdot = dR_dphi * eul_rate[0] + dR_dth * eul_rate[1]
    e1 = np.array([rho - g["los_d"][0]] + [_wrap(m - d) for m, d in ((qe, g["los_d"][1]), (qb, g["los_d"][2]),
                                                                       (phi, g["euler_d"][0]), (th, g["euler_d"][1]),
                                                                       (psi, g["euler_d"][2]))])
    w_d = R @ g["euler_d_rate"]
    e2 = np.concatenate([g["los_rate"] - g["los_d_rate"], om - w_d])
    e1dot = np.concatenate([e2[:3], Rinv @ e2[3:]])
    s = np.sign(e1) * np.abs(e1) ** a
    with np.errstate(divide="ignore"):
        eta = np.where(np.abs(e1) > p.delta, a * np.abs(e1) ** (a - 1.0), a * p.delta ** (a - 1.0))
    nu = np.concatenate([-k1[:3] * s[:3], -R @ (k1[3:] * s[3:])])
    nudot = np.concatenate([-k1[:3] * eta[:3] * e1dot[:3], -Rdot @ (k1[3:] * s[3:]) - R @ (k1[3:] * eta[3:] * e1dot[3:])])
    z = e2 - nu
    e = np.concatenate([e1, e2]) / np.array(p.input_scale)
    basis = np.exp(-np.array([np.sum((e - c) ** 2) for c in p.centres()]) / (2 * p.sigma ** 2))
    # the second network: phi_j times a Gaussian of the previous command (section 7)
    basis_d = basis * np.exp(-np.array([np.sum((command - c) ** 2) for c in p.centres()]) / (2 * p.sigma ** 2))
    w_hat = theta.T @ basis
    w_hat_d = theta_d.T @ basis_d if p.theorem == 2 else np.zeros(6)
    rd, qed, qbd = g["los_rate"]
    F = np.array([rho * qed ** 2 + rho * qbd ** 2 * np.cos(qe) ** 2 - g["los_d_acc"][0],
                  (-2 * rd * qed - rho * qbd ** 2 * np.sin(qe) * np.cos(qe)) / rho - g["los_d_acc"][1],
                  (-2 * rd * qbd * np.cos(qe) + 2 * rho * qed * qbd * np.sin(qe)) / (rho * np.cos(qe))
                  - g["los_d_acc"][2]])
    F_att = -np.cross(om, J * om) / J - Rdot @ g["euler_d_rate"] - R @ g["euler_d_acc"]
    At_e1 = np.concatenate([e1[:3], Rinv.T @ e1[3:]])
    v = (-np.concatenate([F, F_att]) - At_e1 + nudot - k2 * np.sign(z) * np.abs(z) ** a - p.k3 * np.sign(z)
         - w_hat - w_hat_d)
    u_c = np.array([-v[0], -rho * v[1], rho * np.cos(qe) * v[2]])
    C_li = _rz(qe) @ _ry(qb)
    C_bi = _ry(th) @ _rx(phi) @ _rz(psi)
    force = np.clip(p.mass * (C_bi @ C_li.T @ u_c), -p.force_max, p.force_max)
    torque = np.clip(J * v[3:], -p.torque_max, p.torque_max)
    bound = np.array(p.theta_max)                          # one per channel (column)

    def adapt(w, gamma, phi):
        return np.clip((1 - period * gamma * p.lam) * w + period * gamma * np.outer(phi, z), -bound, bound)
    new_d = adapt(theta_d, p.gamma_delta, basis_d) if p.theorem == 2 else theta_d
    new_command = np.concatenate([force / p.force_max, torque / p.torque_max])
    return force, torque, w_hat, adapt(theta, p.gamma, basis), new_d, new_command


def test_golden_agrees_with_the_float64_step(unit):
    """Inside rows (weights within their bounds, commands in [-1, 1]): force, torque, w_hat, the new weights
    and the new command within 1e-4 (relative to the value, or to the output's scale: its limit, the weight
    bound, 1)."""
    p = unit.params
    b = unit.gate_classes(6 * 150, seed=21)["inside"]
    assert np.mean(np.any(b.state["command"] != 0, axis=1)) > 0.8      # the command input matters here
    out, state = unit.golden(b.state, b.input)
    assert np.all(out["status"] & rec.STATUS_INVALID_INPUT == 0)
    n, bound = p.nodes, np.array(p.theta_max)
    worst = {}
    for r in range(b.input.shape[0]):
        th0 = b.state["theta"][r].reshape(n, 6).astype(np.float64)
        td0 = b.state["theta_delta"][r].reshape(n, 6).astype(np.float64)
        u0 = b.state["command"][r].astype(np.float64)
        f, t, w, th1, td1, u1 = reference_step(p, unit.period, th0, td0, u0, b.input[r])
        for name, got, want, scale in (("force", out["force"][r], f, p.force_max),
                                       ("torque", out["torque"][r], t, p.torque_max),
                                       ("w_hat", out["w_hat"][r], w, n * bound),
                                       ("theta", state["theta"][r].reshape(n, 6), th1, bound),
                                       ("theta_delta", state["theta_delta"][r].reshape(n, 6), td1, bound),
                                       ("command", state["command"][r], u1, 1.0)):
            err = np.abs(got.astype(np.float64) - want) / np.maximum(np.abs(want), scale)
            worst[name] = max(worst.get(name, 0.0), float(err.max()))
    assert all(v < 1e-4 for v in worst.values()), worst


# ----------------------------------------------------------------------------- safety


def _valid_states(unit, n: int, seed: int) -> np.ndarray:
    return unit.gate_classes(6 * n, seed)["inside"].state[:n].copy()


def test_invalid_rows_leave_the_weights_bit_identical_and_zero_the_command(unit):
    classes = unit.gate_classes(6 * 600, seed=22)
    inp = np.concatenate([classes["outside"].input, classes["special"].input])
    state = _valid_states(unit, inp.shape[0], seed=23)
    run = runner(unit, "x86")
    for out, after in (unit.golden(state, inp), run.records(Batch(state, inp))):
        invalid = (out["status"] & rec.STATUS_INVALID_INPUT) != 0
        assert invalid.sum() >= 600
        assert np.all(out["status"][invalid] == rec.STATUS_INVALID_INPUT)
        for name in ("theta", "theta_delta"):
            assert np.array_equal(state[name][invalid].view(np.uint32), after[name][invalid].view(np.uint32))
        assert np.all(after["command"][invalid].view(np.uint32) == 0)   # the output was 0: so is the command
        for name in ("force", "torque", "w_hat"):
            assert np.all(out[name][invalid].view(np.uint32) == 0)     # +0 exactly


def test_every_weight_finite_and_within_its_bound(unit):
    """After every step, from any state (random bits included): the gate classes and a sequence in C."""
    for b in unit.gate_classes(6 * 500, seed=24).values():
        out, state = unit.golden(b.state, b.input)
        assert unit.check_state(state) == [] and unit.check_outputs(out) == []
    b = unit.gate_classes(6 * 500, seed=24)["state"]
    out, after = runner(unit, "x86").records(b)
    assert unit.check_state(after) == []
    bound = np.tile(np.array(unit.params.theta_max, dtype=np.float32), unit.params.nodes)
    bits = b.state["theta"].view(np.uint32) & 0x7FFFFFFF
    with np.errstate(invalid="ignore"):
        bad = (bits >= 0x7F800000).any(axis=1) | (np.abs(b.state["theta"]) > bound).any(axis=1)
        bad_u = ~np.isfinite(b.state["command"]).all(axis=1) | (np.abs(b.state["command"]) > 1).any(axis=1)
    assert bad_u.sum() > 100
    assert np.all(out["status"][bad | bad_u] & rec.STATUS_STATE_REPAIRED)


def test_repair_resets_non_finite_and_clips_beyond_the_bound():
    unit = RbfUnit(PAPER)
    b = unit.gate_classes(6 * 10, seed=25)["inside"]
    state = b.state[:4].copy()
    inp = b.input[:4].copy()
    inp["los"][3, 0] = np.nan                                  # row 3 invalid: the repair alone shows
    for r in range(4):
        state["theta"][r, :4] = [np.nan, -np.inf, 7.0, -3e38]   # columns 0-3: bounds 0.1, 0.001, 0.001, 0.01
        state["theta_delta"][r, 3:5] = [0.5, -np.float32(1e-45)]  # column 3's bound 0.01; a subnormal stays
    _, after = unit.golden(state, inp)
    c_out, c_after = runner(unit, "x86").records(Batch(state, inp))
    assert compare_fields(after, c_after) == []
    assert list(after["theta"][3, :4]) == [0.0, 0.0, np.float32(0.001), -np.float32(0.01)]
    assert after["theta_delta"][3, 3] == np.float32(0.01) and after["theta_delta"][3, 4] == -np.float32(1e-45)
    assert np.all(c_out["status"] & rec.STATUS_STATE_REPAIRED)


def test_a_result_beyond_the_guard_is_invalid_and_leaves_the_weights():
    """k2 = 3e38 (a valid float32): K2 sig(z)^alpha overflows for most rows; the guard (sum |v'| + sum |z|
    <= 1e30) makes them INVALID_INPUT with zero output, the weights unchanged and the command 0, in golden and C."""
    unit = RbfUnit(params_from_mapping({**PAPER.to_mapping(), "k2": [3e38] * 6}))
    b = unit.gate_classes(6 * 200, seed=29)["inside"]
    out, after = unit.golden(b.state, b.input)
    c_out, c_after = runner(unit, "x86").records(b)
    assert compare_fields(out, c_out) == [] and compare_fields(after, c_after) == []
    invalid = out["status"] == rec.STATUS_INVALID_INPUT
    assert invalid.sum() > 100
    for name in ("theta", "theta_delta"):
        assert np.array_equal(b.state[name][invalid].view(np.uint32), after[name][invalid].view(np.uint32))
    assert np.all(after["command"][invalid].view(np.uint32) == 0)
    assert unit.check_outputs(out) == [] and unit.check_state(after) == []


def test_theorem_1_leaves_theta_delta_zero_and_adapts_theta():
    unit = RbfUnit(THEOREM1)
    seqs = unit.gate_sequences(3, 300, seed=26)
    state = unit.init_state(3)
    run = runner(unit, "x86")
    c_state = state.copy()
    for t in range(seqs.shape[1]):
        x = np.ascontiguousarray(seqs[:, t])
        out, state = unit.golden(state, x)
        c_out, c_state = run.records(Batch(c_state, x))
        assert compare_fields(out, c_out) == []
    assert compare_fields(state, c_state) == []
    assert np.all(state["theta_delta"].view(np.uint32) == 0)
    assert np.all(np.any(state["theta"] != 0, axis=1))


def _golden_and_c(unit, state, inp):
    """One step in golden and C (x86), checked bit for bit; (out, state after)."""
    out, after = unit.golden(state, inp)
    c_out, c_after = runner(unit, "x86").records(Batch(state, inp))
    assert compare_fields(out, c_out) == [] and compare_fields(after, c_after) == []
    return out, after


def test_theorem_2_second_network_sees_the_command():
    """From init over a sequence (golden and C alike): the command becomes non-zero and theta_delta
    departs from theta (the first reconstruction made it an exact copy); on one step, changing only the
    command changes force and theta_delta but not w_hat or theta."""
    unit = RbfUnit(PAPER)
    seqs = unit.gate_sequences(3, 20, seed=30)
    state = unit.init_state(3)
    run = runner(unit, "x86")
    c_state = state.copy()
    for t in range(seqs.shape[1]):
        x = np.ascontiguousarray(seqs[:, t])
        out, state = unit.golden(state, x)
        c_out, c_state = run.records(Batch(c_state, x))
        assert compare_fields(out, c_out) == []
    assert compare_fields(state, c_state) == []
    assert np.all(np.any(state["command"] != 0, axis=1))
    diff = np.abs(state["theta_delta"] - state["theta"]).max(axis=1)
    assert np.all(diff > 0.01 * np.abs(state["theta"]).max(axis=1))
    b = unit.gate_classes(6 * 200, seed=31)["inside"]
    other = b.state.copy()
    other["command"] = -b.state["command"][:, ::-1] * np.float32(0.5) + np.float32(0.25)
    out0, after0 = _golden_and_c(unit, b.state, b.input)
    out1, after1 = _golden_and_c(unit, other, b.input)
    assert np.array_equal(out0["w_hat"], out1["w_hat"]) and np.array_equal(after0["theta"], after1["theta"])
    assert np.mean(np.any(out0["force"] != out1["force"], axis=1)) > 0.5
    assert np.mean(np.any(after0["theta_delta"] != after1["theta_delta"], axis=1)) > 0.9


def test_the_command_is_the_normalised_limited_output(unit):
    """After a valid step the state's command is (force / force_max, torque / torque_max) of this step's
    limited output (to float32 rounding), in [-1, 1], exactly +-1 where a component was limited."""
    p = unit.params
    for name, b in unit.gate_classes(6 * 300, seed=32).items():
        out, after = _golden_and_c(unit, b.state, b.input)
        valid = (out["status"] & rec.STATUS_INVALID_INPUT) == 0
        want = np.concatenate([out["force"] / p.force_max, out["torque"] / p.torque_max], axis=1)[valid]
        got = after["command"][valid].astype(np.float64)
        assert np.all(np.abs(got - want) <= 1.2e-7 * np.abs(want)), name
        assert np.all(np.abs(got) <= 1.0)
        limited = np.concatenate([np.abs(out["force"]) == np.float32(p.force_max),
                                  np.abs(out["torque"]) == np.float32(p.torque_max)], axis=1)[valid]
        assert np.all(np.abs(got[limited]) == 1.0)
        if name == "saturated":
            assert limited.sum() > 100


def test_a_garbage_command_is_repaired():
    """Non-finite command entries become 0, entries beyond +-1 become +-1 (sign kept), with
    STATUS_STATE_REPAIRED: the step then equals the step from the repaired command, bit for bit
    (theorem 2 reads it); on an invalid step the command is 0 afterwards, the bit still set."""
    unit = RbfUnit(PAPER)
    b = unit.gate_classes(6 * 60, seed=33)["inside"]
    garbage = b.state.copy()
    repaired = b.state.copy()
    above = np.nextafter(np.float32(1.0), np.float32(2.0))
    garbage["command"][:] = [np.nan, np.inf, -np.inf, 1.5, -3e38, above]
    repaired["command"][:] = [0.0, 0.0, 0.0, 1.0, -1.0, 1.0]
    inp = b.input.copy()
    inp["los"][:10, 0] = np.nan                                 # ten invalid rows
    out_g, after_g = _golden_and_c(unit, garbage, inp)
    out_r, after_r = _golden_and_c(unit, repaired, inp)
    assert np.all(out_g["status"] & rec.STATUS_STATE_REPAIRED)
    assert np.array_equal(out_g["status"] & ~np.uint32(rec.STATUS_STATE_REPAIRED), out_r["status"])
    assert not np.any(out_r["status"] & rec.STATUS_STATE_REPAIRED)
    for name in ("force", "torque", "w_hat"):
        assert np.array_equal(out_g[name].view(np.uint32), out_r[name].view(np.uint32))
    assert compare_fields(after_g, after_r) == []
    assert np.all(after_g["command"][:10].view(np.uint32) == 0)
    # the repaired command is what theorem 2 reads: a different (valid) command gives a different step
    other = repaired.copy()
    other["command"][:] = [0.5, 0.0, 0.0, 1.0, -1.0, 1.0]
    out_o, _ = _golden_and_c(unit, other, inp)
    assert np.any(out_o["force"][10:] != out_r["force"][10:])


def test_the_weight_bound_is_one_per_channel(unit):
    """|theta_jk|, |theta_delta_jk| <= theta_max[k] per column k, and the clip acts at that column's own bound
    (each column reaches exactly its bound in the saturated class), golden and C alike."""
    p = unit.params
    b = unit.gate_classes(6 * 600, seed=34)["saturated"]
    out, after = _golden_and_c(unit, b.state, b.input)
    bound = np.array(p.theta_max, dtype=np.float32)
    assert len(set(bound.tolist())) > 1                         # the columns' bounds differ
    for name in ("theta", "theta_delta") if p.theorem == 2 else ("theta",):
        w = np.abs(after[name].reshape(-1, p.nodes, 6))
        assert np.all(w <= bound)
        assert np.all(w.max(axis=(0, 1)) == bound), name
    assert np.any(out["status"] & rec.STATUS_WEIGHT_BOUND)


def test_sequences_adapt_and_some_reach_the_bound():
    unit = RbfUnit(PAPER)
    seqs = unit.gate_sequences(3, 400, seed=27)
    out = unit.golden_sequences(seqs)
    assert not np.any(out["status"] & rec.STATUS_INVALID_INPUT)
    w = out["w_hat"]
    assert np.all(np.abs(w[:, -1]).max(axis=1) > 0) and np.all(np.abs(w[:, -1] - w[:, 10]).max(axis=1) > 0)
    assert np.any(out["status"][0] & rec.STATUS_WEIGHT_BOUND)      # the approach sequence
    assert not np.all(out["status"] & rec.STATUS_FORCE_LIMITED)   # fine tracking is not saturated


def test_a_one_ulp_change_of_a_weight_changes_the_output():
    """The weights reach the output: one ulp more on one weight changes what the gate compares (the
    output or the state after) on nearly every row where the weight is not below its update (|theta_jk| >=
    |a z_k|; else the ulp can vanish in b theta_jk + phi_j a z_k, and in w_hat when phi_j ulp(theta_jk)
    is below half an ulp of the sum), and w_hat itself on most rows; golden and C alike."""

    unit = RbfUnit(PAPER)
    b = unit.gate_classes(6 * 300, seed=28)["inside"]
    out0, state0 = unit.golden(b.state, b.input)
    nodes, k = unit.params.nodes, 1
    z_k = golden.law(unit.constants, b.input)[1][k]
    run = runner(unit, "x86")
    seen_w = np.zeros(b.input.shape[0], dtype=bool)
    for j in range(nodes):
        s = b.state.copy()
        w = s["theta"].reshape(-1, nodes, 6)
        sel = np.abs(w[:, j, k]) >= np.abs(unit.constants.a * z_k)
        assert sel.sum() > 60
        w[:, j, k] = np.nextafter(w[:, j, k], np.float32(np.inf))
        out1, state1 = unit.golden(s, b.input)
        c_out1, c_state1 = run.records(Batch(s, b.input))
        assert compare_fields(out1, c_out1) == [] and compare_fields(state1, c_state1) == []
        differs = np.any(out1.view(np.uint32).reshape(len(out1), -1) != out0.view(np.uint32).reshape(len(out0), -1), axis=1)
        differs |= np.any(state1.view(np.uint32).reshape(len(s), -1) != state0.view(np.uint32).reshape(len(s), -1), axis=1)
        assert differs[sel].mean() > 0.95  # b (theta + ulp) can round as b theta, a clip can hide it
        seen_w |= out1["w_hat"][:, k] != out0["w_hat"][:, k]
    assert seen_w.mean() > 0.75


# ----------------------------------------------------------------------------- the CLI


@pytest.mark.parametrize("edit, message", [
    (lambda d: d.pop("k1"), "missing key 'k1'"),
    (lambda d: d.update(nodes=16), "'nodes': must be in [2, 15], got 16"),
    (lambda d: d.update(theta_max=[0.1, -1.0, 0.1, 0.1, 0.1, 0.1]), "'theta_max'[1]: must be > 0, got -1.0"),
    (lambda d: d.update(theta_max_orbit=1.0), "unknown key 'theta_max_orbit'"),
])
@pytest.mark.parametrize("command", [["codegen", "--unit", "rbf", "--out", "{out}"], ["verify", "--unit", "rbf"]])
def test_parameter_errors_are_one_line_through_the_cli(tmp_path, capsys, edit, message, command):
    data = PAPER.to_mapping()
    edit(data)
    path = tmp_path / "p.json"
    path.write_text(json.dumps(data))
    argv = [a.replace("{out}", str(tmp_path / "gen")) for a in command] + ["--params", str(path)]
    code = cli.main(argv)
    res = capsys.readouterr()
    assert code == 2 and res.out == ""
    assert res.err == f"staregen {command[0]}: error: {path}: {message}\n"
    assert not (tmp_path / "gen").exists()


def test_the_unit_needs_its_parameters(capsys):
    assert cli.main(["verify", "--unit", "rbf", "--vectors", "10"]) == 2
    assert "unit rbf needs --params FILE" in capsys.readouterr().err


# ----------------------------------------------------------------------------- the generated C


def test_the_package_self_test_passes_and_clang_compiles_it(tmp_path):
    """The flight package's self-test (codegen.package.selftest) with the gate classes' vectors returns 0
    on x86; gcc and clang compile the unit with the flight flags (-Werror)."""


    unit = RbfUnit(PAPER, name="stare_rbf")
    files = {**unit.sources(), **selftest_sources("stare", [make_vectors(unit, 128, 0)])}
    for name, text in files.items():
        (tmp_path / name).write_text(text)
    (tmp_path / "main.c").write_text('#include <stdio.h>\nint stare_selftest(void);\n'
                                     'int main(void) { printf("%d\\n", stare_selftest()); return 0; }\n')
    objs = []
    for name in sorted(n for n in files if n.endswith(".c")):
        obj = tmp_path / (name[:-2] + ".o")
        subprocess.run(["gcc", *COMMON, "-c", str(tmp_path / name), "-o", str(obj)], check=True, capture_output=True)
        objs.append(str(obj))
    subprocess.run(["gcc", "-O1", str(tmp_path / "main.c"), *objs, "-o", str(tmp_path / "st")], check=True,
                   capture_output=True)
    assert subprocess.run([str(tmp_path / "st")], capture_output=True, text=True, check=True).stdout == "0\n"
    if shutil.which("clang"):
        flags = [f for f in COMMON if f != "-fexcess-precision=standard"]
        res = subprocess.run(["clang", *flags, "-c", str(tmp_path / "stare_rbf.c"), "-o", str(tmp_path / "c.o")],
                             capture_output=True, text=True)
        assert res.returncode == 0, res.stderr


def test_the_fuzzer_holds_the_weights_to_their_bounds():
    """tools/fuzz.py applies Unit.check_state to the golden states: random-bit states and inputs through
    the sanitizer build give no problem, and a planted state check is reported."""

    unit = RbfUnit(PAPER)
    assert fuzz(unit, 5_000, seed=3, log=lambda *_: None).ok
    planted = RbfUnit(PAPER)
    planted.check_state = lambda state: ["planted"] if state.shape[0] else []
    result = fuzz(planted, 1_000, seed=3, log=lambda *_: None)
    assert result.mismatches == 0 and result.invariant_problems == ["planted"]


def test_the_package_records_the_values_it_bakes_in():
    """values_sha256 (the manifest's record of the parameter file) changes with any baked-in value: a
    gain, the period; and not with how the file wrote a number."""
    p = paper_params()
    base = RbfUnit(p, 0.1).values_sha256()
    assert len(base) == 64 and base == RbfUnit(paper_params(k3=1e-07), 0.1).values_sha256()
    assert base != RbfUnit(p, 0.05).values_sha256()
    assert base != RbfUnit(paper_params(k3=2e-7), 0.1).values_sha256()
