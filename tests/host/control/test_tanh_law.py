"""Paper 000's tanh law (host float64): pieces against independent truth, the section 4.2 example
against the issue-7 acceptance numbers, the 180° guard, and parameter-file errors.

The two continuous 40 s runs dominate the time (~8 s and ~16 s on an idle core); they are
computed once per process (module-scoped fixtures).
"""
import json
import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp
from scipy.linalg import expm
from scipy.spatial.transform import Rotation

from host.plant import rigid_body
from host.core import rotations as rot
from host.sim import tanh_example as ex
from host.control import tanh_law as tl
from host.errors import HostError

RNG = np.random.default_rng(20260521)
PARAMS = ex.paper_parameters()
C = tl.compile_constants(PARAMS)


def as_mat(m):
    return tl._as_mat(np.asarray(m, dtype=float))


def random_rotation():
    return Rotation.random(random_state=RNG).as_matrix()


def rotation_of(angle_deg, axis):
    axis = np.asarray(axis, dtype=float)
    return Rotation.from_rotvec(np.deg2rad(angle_deg) * axis / np.linalg.norm(axis)).as_matrix()


def virtual_rate_of(R_e):
    """ω_ev = E⁻¹ g(x1) as a function of R_e alone (eq. 10)."""
    q0, x1, regular = tl.attitude_error(as_mat(R_e), PARAMS.q0_min)
    assert regular
    return np.array(tl.jacobian_solve(q0, x1, tl.virtual_rate_target(C, x1)))


# ----------------------------------------------------------------------------- scenario data


def test_target_attitude_is_eq32():
    np.testing.assert_allclose(ex.target_attitude(), np.array(ex.RT_EQ32), atol=1e-6)


def test_initial_attitude_is_eq28_on_so3():
    R = ex.initial_attitude()
    np.testing.assert_allclose(R @ R.T, np.eye(3), atol=1e-14)
    assert np.linalg.det(R) == pytest.approx(1.0, abs=1e-14)
    assert np.max(np.abs(R - np.array(ex.RC0_EQ28))) < 1e-3


# ----------------------------------------------------------------------------- attitude error, E


def test_error_vector_is_vector_part_of_error_quaternion():
    for _ in range(50):
        R_t, R_c = random_rotation(), random_rotation()
        R_e = R_t.T @ R_c
        q0, e, regular = tl.attitude_error(tl.error_matrix(as_mat(R_t), as_mat(R_c)), PARAMS.q0_min)
        q = Rotation.from_matrix(R_e).as_quat()  # scalar last, active rotation, independent of tl
        q = q if q[3] >= 0 else -q
        if not regular:
            continue
        np.testing.assert_allclose(e, q[:3], atol=1e-14)
        assert q0 == pytest.approx(q[3], abs=1e-14)
        s = math.sqrt(1.0 + np.trace(R_e))
        np.testing.assert_allclose(e, rot.vee(R_e - R_e.T) / (2 * s), atol=1e-15)


def test_E_eq8_equals_half_q0_I_plus_skew_e():
    for _ in range(50):
        R_e = random_rotation()
        q0, e, regular = tl.attitude_error(as_mat(R_e), PARAMS.q0_min)
        if not regular:
            continue
        E8 = np.array(tl.error_jacobian(as_mat(R_e), e, 2.0 * q0))
        np.testing.assert_allclose(E8, 0.5 * (q0 * np.eye(3) + rot.skew(np.array(e))), atol=1e-14)
        v = RNG.normal(size=3)
        np.testing.assert_allclose(tl.jacobian_apply(q0, e, tuple(v)), E8 @ v, atol=1e-14)
        np.testing.assert_allclose(E8 @ np.array(tl.jacobian_solve(q0, e, tuple(v))), v, atol=1e-12)


def test_error_kinematics_e_dot_is_E_omega_e():
    # eq. 5 with Ṙ_e = R_e[ω_e]×: propagate R_e exactly for a constant ω_e, central difference.
    for _ in range(10):
        R_e, w_e, h = rotation_of(RNG.uniform(5, 170), RNG.normal(size=3)), RNG.normal(size=3), 1e-6
        e_plus = tl.attitude_error(as_mat(R_e @ expm(rot.skew(w_e) * h)), 0.01)[1]
        e_minus = tl.attitude_error(as_mat(R_e @ expm(-rot.skew(w_e) * h)), 0.01)[1]
        q0, e, _ = tl.attitude_error(as_mat(R_e), 0.01)
        np.testing.assert_allclose((np.array(e_plus) - e_minus) / (2 * h),
                                   tl.jacobian_apply(q0, e, tuple(w_e)), atol=1e-8)


# ----------------------------------------------------------------------------- f (11) and ω̇_ev


def test_shaping_is_continuous_in_value_and_slope_at_eta():
    g, eta = PARAMS.gamma, PARAMS.eta
    assert C.r1 == pytest.approx((2 - g) * eta ** (g - 1), rel=1e-15)
    assert C.r2 == pytest.approx((g - 1) * eta ** (g - 2), rel=1e-15)
    for x in (eta, -eta):
        inside = tl.shaping(x, g, eta, C.r1, C.r2)
        outside = tl.shaping(x * (1 + 1e-12), g, eta, C.r1, C.r2)
        assert inside == pytest.approx(math.copysign(eta ** g, x), rel=1e-12)
        assert outside == pytest.approx(inside, rel=1e-10)
        assert tl.shaping_slope(x, g, eta, C.r1, C.r2) == pytest.approx(g * eta ** (g - 1), rel=1e-12)
    assert tl.shaping(0.0, g, eta, C.r1, C.r2) == 0.0
    assert tl.shaping(0.5, g, eta, C.r1, C.r2) == pytest.approx(0.5 ** g, rel=1e-15)


@pytest.mark.parametrize("x1", [(0.0004, -0.2, 0.1), (0.3, -0.5, 0.6), (-0.0009, 0.0002, 0.05),
                                (0.55, 0.55, 0.55)],
                         ids=["one-inside-eta", "large", "two-inside-eta", "near-144deg"])
def test_virtual_rate_derivative_matches_finite_difference(x1):
    x1 = np.array(x1)
    q0 = math.sqrt(1 - x1 @ x1)
    R_e = Rotation.from_quat([*x1, q0]).as_matrix()
    w_e, h = RNG.normal(scale=0.2, size=3), 1e-6
    fd = (virtual_rate_of(R_e @ expm(rot.skew(w_e) * h))
          - virtual_rate_of(R_e @ expm(-rot.skew(w_e) * h))) / (2 * h)
    w_ev = virtual_rate_of(R_e)
    analytic = tl.virtual_rate_derivative(C, q0, tuple(x1), tuple(w_e), tuple(w_ev))
    np.testing.assert_allclose(analytic, fd, rtol=1e-6, atol=1e-7 * (1 + np.abs(fd).max()))


def test_dynamics_term_F_eq7():
    # J ω̇_e = F + u (+ d) along the true motion of R_c and R_t with a moving target.
    J, J_inv = np.array(ex.J_EQ27), np.linalg.inv(ex.J_EQ27)
    u, wdot_t = RNG.normal(size=3), RNG.normal(scale=0.01, size=3)

    def rates(t, y):
        Rc, wc, Rt, wt = y[:9].reshape(3, 3), y[9:12], y[12:21].reshape(3, 3), y[21:24]
        wc_dot = J_inv @ (-np.cross(wc, J @ wc) + u)
        return np.concatenate([(Rc @ rot.skew(wc)).ravel(), wc_dot, (Rt @ rot.skew(wt)).ravel(), wdot_t])

    y0 = np.concatenate([random_rotation().ravel(), RNG.normal(scale=0.2, size=3),
                         random_rotation().ravel(), RNG.normal(scale=0.05, size=3)])

    def w_e_at(y):
        R_e = y[12:21].reshape(3, 3).T @ y[:9].reshape(3, 3)
        return y[9:12] - R_e.T @ y[21:24]

    h = 1e-4
    ends = [solve_ivp(rates, (0, s * h), y0, method="DOP853", rtol=1e-13, atol=1e-14).y[:, -1] for s in (1, -1)]
    w_e_dot = (w_e_at(ends[0]) - w_e_at(ends[1])) / (2 * h)
    Rc, wc, Rt = y0[:9].reshape(3, 3), y0[9:12], y0[12:21].reshape(3, 3)
    R_e = Rt.T @ Rc
    F = tl.dynamics_term(C, as_mat(R_e), tuple(wc), tuple(w_e_at(y0)), tuple(wdot_t))
    np.testing.assert_allclose(J @ w_e_dot, np.array(F) + u, atol=1e-7)


# ----------------------------------------------------------------------------- law pieces


def test_torque_is_bounded_by_k1_k2_k3():
    bound = PARAMS.k1 + PARAMS.k2 + PARAMS.k3
    for _ in range(200):
        varpi, R_c, w_c = RNG.normal(scale=10, size=3), random_rotation(), RNG.normal(scale=5, size=3)
        out = tl.evaluate_law(C, tuple(varpi), as_mat(R_c), tuple(w_c), as_mat(random_rotation()),
                              tuple(RNG.normal(size=3)), tuple(RNG.normal(size=3)))
        assert np.all(np.abs(out.torque) <= bound)
        assert np.all(np.isfinite(out.varpi_dot))


def test_delta_regularisation_of_section_4_2():
    assert tl.regularised_inverse_square(C, 0.0) == pytest.approx(1000.0)
    assert tl.regularised_inverse_square(C, 0.0005) == pytest.approx(1 / 0.0015)
    assert tl.regularised_inverse_square(C, 0.001) == pytest.approx(500.0)   # ≤ threshold: regularised
    assert tl.regularised_inverse_square(C, 0.002) == pytest.approx(500.0)   # plain 1/(δᵀδ)


def test_disturbance_compensation_eq20():
    gain = C.J_inv_norm * PARAMS.d_max
    assert C.J_inv_norm == pytest.approx(1 / np.linalg.eigvalsh(np.array(ex.J_EQ27)).min(), rel=1e-14)
    outer = tl.disturbance_compensation(C, (0.3, -0.4, 0.0))
    np.testing.assert_allclose(outer, (0.6 * gain, -0.8 * gain, 0.0), rtol=1e-14)
    # axis-aligned δ: both branches give gain·sign(δ_i) at ‖δ‖ = n1 (continuous there)
    at = tl.disturbance_compensation(C, (PARAMS.n1, 0.0, 0.0))
    just_out = tl.disturbance_compensation(C, (PARAMS.n1 * (1 + 1e-12), 0.0, 0.0))
    assert at[0] == pytest.approx(gain, rel=1e-12) and just_out[0] == pytest.approx(gain, rel=1e-12)
    inner = tl.disturbance_compensation(C, (-1e-5, 2e-4, 0.0))
    np.testing.assert_allclose(inner, [gain * math.copysign(abs(d) ** 0.8, d) / PARAMS.n1 ** 0.8
                                       for d in (-1e-5, 2e-4, 0.0)], rtol=1e-14)


def test_controller_class_mirrors_sampled_simulation():
    sc = ex.paper_scenario()
    hist = ex.simulate_sampled(sc, 0.1, 1.0, 0.1)  # one plant RK4 step per control period
    ctrl = tl.TanhController(PARAMS, period=0.1)
    body = ex.plant(sc)
    y = ex.initial_state(sc)
    for k in range(10):
        assert ctrl.varpi == tuple(hist["varpi"][k])
        out = ctrl.step(np.array(rigid_body.rows(y)), np.array(y[9:12]), np.array(sc.R_t))
        assert out.torque == tuple(hist["u"][k])
        y = body.rk4_step(0.1 * k, y, 0.1, out.torque)


# ----------------------------------------------------------------------------- 180° and bad input


@pytest.mark.parametrize("angle", [179.5, 179.99, 180.0])
def test_near_180_law_is_finite_bounded_and_flagged(angle):
    R_t = ex.target_attitude()
    for _ in range(20):
        R_c = R_t @ rotation_of(angle, RNG.normal(size=3))
        out = tl.evaluate_law(C, tuple(RNG.normal(size=3)), as_mat(R_c), tuple(RNG.normal(scale=0.3, size=3)),
                              as_mat(R_t), (0.0, 0.0, 0.0), (0.0, 0.0, 0.0))
        assert out.status == tl.STATUS_SINGULAR
        assert np.all(np.isfinite(out.torque)) and np.all(np.abs(out.torque) <= PARAMS.k2 + PARAMS.k3)
        assert out.varpi_dot == (0.0, 0.0, 0.0)
        assert np.linalg.norm(out.x1) == pytest.approx(math.sin(math.radians(angle) / 2), abs=1e-9)


def test_near_180_error_vector_joins_eq4():
    # just inside the regular region, the 180°-safe form and eq. 4 agree (continuous hand-over)
    R_e = rotation_of(178.0, (1.0, -2.0, 0.5))
    q0, e, regular = tl.attitude_error(as_mat(R_e), PARAMS.q0_min)
    assert regular
    np.testing.assert_allclose(tl.error_vector_near_180(as_mat(R_e)), e, atol=1e-12)


def test_start_at_179_5_degrees_recovers_without_nan():
    R_c0 = ex.target_attitude() @ rotation_of(179.5, (1.0, 2.0, -0.5))
    sc = ex.paper_scenario(R_c0=R_c0, w_c0=(0.0, 0.0, 0.0))
    hist = ex.simulate_sampled(sc, 0.1, 40.0, 1e-3)
    m = ex.metrics_of(hist)
    assert m["finite"] and m["invalid_samples"] == 0
    assert hist["status"][0] == tl.STATUS_SINGULAR and m["singular_samples"] > 0
    assert m["u_max"] <= PARAMS.k1 + PARAMS.k2 + PARAMS.k3
    assert m["e_final"] <= 2e-5
    # the continuous law through the hand-over (fallback -> regular) stays finite as well
    short = ex.simulate_continuous(sc, 3.0, 5e-4)
    assert ex.metrics_of(short)["finite"] and np.any(short["status"] == tl.STATUS_OK)


def test_non_finite_input_gives_zero_torque_and_flag():
    R = as_mat(np.eye(3))
    for bad in (math.nan, math.inf):
        out = tl.evaluate_law(C, (0.0, 0.0, 0.0), R, (bad, 0.0, 0.0), R, (0.0, 0.0, 0.0), (0.0, 0.0, 0.0))
        assert out.status == tl.STATUS_INVALID_INPUT
        assert out.torque == (0.0, 0.0, 0.0) and out.varpi_dot == (0.0, 0.0, 0.0)


def test_euler_update_clamps_varpi():
    assert tl.euler_update((1.0, -2.0, 0.0), (10.0, -1e9, 1.0), 0.1, 1e6) == (2.0, -1e6, 0.1)


# ----------------------------------------------------------------------------- parameter files


def write_params(tmp_path, data, suffix=".toml"):
    path = tmp_path / f"tanh{suffix}"
    if suffix == ".json":
        path.write_text(json.dumps(data))
    else:
        lines = []
        for key, value in data.items():
            lines.append(f"{key} = {json.dumps(value)}")
        path.write_text("\n".join(lines) + "\n")
    return path


@pytest.mark.parametrize("suffix", [".toml", ".json"])
def test_parameter_file_round_trip(tmp_path, suffix):
    path = write_params(tmp_path, PARAMS.to_mapping(), suffix)
    assert tl.load_params(path) == PARAMS


@pytest.mark.parametrize("edit, message", [
    (lambda d: d.pop("k4"), "missing key 'k4'"),
    (lambda d: d.update(k2=-1.5), "'k2' = -1.5 must be > 0"),
    (lambda d: d.update(eps3=0.0), "'eps3' = 0.0 must be > 0"),
    (lambda d: d.update(gamma=1.0), "'gamma' = 1.0 must be in (0, 1)"),
    (lambda d: d.update(gamma=0.0), "'gamma' = 0.0 must be in (0, 1)"),
    (lambda d: d.update(gamma=1.2), "'gamma' = 1.2 must be in (0, 1)"),
    (lambda d: d.update(k6=1.0), "unknown key 'k6'"),
    (lambda d: d.update(beta1="0.3"), "'beta1' must be a finite number, got '0.3'"),
    (lambda d: d.update(inertia=[[1.0, 0.0], [0.0, 1.0]]), "'inertia' must be a finite 3x3 matrix"),
    (lambda d: d.update(inertia=[[1.0, 2.0, 0.0], [2.0, 1.0, 0.0], [0.0, 0.0, 1.0]]),
     "'inertia' must be positive definite"),
])
@pytest.mark.parametrize("suffix", [".toml", ".json"])
def test_parameter_file_errors_are_precise_one_liners(tmp_path, suffix, edit, message):
    data = PARAMS.to_mapping()
    edit(data)
    path = write_params(tmp_path, data, suffix)
    with pytest.raises(tl.TanhParamsError) as info:
        tl.load_params(path)
    text = str(info.value)
    assert "\n" not in text
    assert text.startswith(f"{path}: ") and message in text


def test_parameter_file_syntax_error_is_one_line(tmp_path):
    path = tmp_path / "bad.toml"
    path.write_text("k1 = = 1\n")
    with pytest.raises(tl.TanhParamsError, match=r"bad\.toml: not valid TOML") as info:
        tl.load_params(path)
    assert "\n" not in str(info.value)


# ----------------------------------------------------------------------------- the example (acceptance)


@pytest.fixture(scope="module")
def reference():
    return ex.run(None, 40.0, 5e-4)


@pytest.fixture(scope="module")
def reference_half_step():
    return ex.run(None, 40.0, 2.5e-4)


def test_continuous_reference_meets_acceptance(reference):
    assert reference["t_settle"] is not None and reference["t_settle"] <= 25.0
    assert reference["e_final"] <= 2e-5
    assert reference["we_final"] <= 1e-5
    assert reference["u_max"] <= 4.5
    assert reference["singular_samples"] == 0 and reference["finite"]


def test_continuous_reference_is_step_converged(reference, reference_half_step):
    assert abs(reference["t_settle"] - reference_half_step["t_settle"]) <= 0.05
    assert reference_half_step["e_final"] == pytest.approx(reference["e_final"], rel=1e-3)


def test_sampled_at_0_1_s_converges_to_the_same_steady_state(reference):
    sampled = ex.run(0.1, 40.0, 5e-4)
    assert sampled["t_settle"] is not None and sampled["t_settle"] <= 25.0
    assert sampled["e_final"] <= 2e-5 and sampled["we_final"] <= 1e-5
    assert sampled["u_max"] <= 4.5
    assert sampled["e_final"] == pytest.approx(reference["e_final"], rel=0.02)


def test_run_writes_metrics_and_figures(tmp_path):
    result = ex.run(0.1, 2.0, 1e-3, tmp_path)
    metrics = json.loads((tmp_path / "metrics.json").read_text())
    for key in ("t_settle", "e_final", "we_final", "u_max"):
        assert key in metrics and metrics[key] == result[key]
    for name, *_ in ex._FIGURES:
        assert (tmp_path / name).read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_run_refuses_an_unconverged_reference_step():
    with pytest.raises(HostError, match="dt <= 0.0005"):
        ex.run(None, 1.0, 1e-3)
