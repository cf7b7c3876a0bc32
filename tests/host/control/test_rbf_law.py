"""Paper 002's float64 law: Lemma 1 (Bhat & Bernstein) on scalar and 2-D examples, the closed z dynamics
of theorem 1 against finite differences of an independent continuous model, the RBF basis against a
direct computation, the weight bound, the refusal of invalid inputs."""
import math

import numpy as np
import pytest

from host.control import rbf_law as law
from host.core.rotations import dcm_from_euler312, euler312_rate_matrix_inverse, los_frame
from codegen.units.rbf.params import example_params
from codegen.units.rbf.unit import RbfUnit
from host.gnc.los import LosMeasurement, from_record, los_kinematics

# ----------------------------------------------------------------------------- Lemma 1


def _settling_time(k, alpha, e0, h_max):
    """RK4 on e' = -k sig(e)^alpha from e0 > 0 until e < 1e-12 e0 (the time left from there is < 1e-5 T).
    The step shrinks with e (h <= 0.05 e^(1-alpha)/k): a fixed step stalls near 0, where the right-hand
    side is not Lipschitz."""
    f = lambda e: -k * abs(e) ** alpha * math.copysign(1.0, e)    # noqa: E731
    t, e = 0.0, e0
    while e >= 1e-12 * e0:
        h = min(h_max, 0.05 * e ** (1 - alpha) / k)
        k1 = f(e); k2 = f(e + 0.5 * h * k1); k3 = f(e + 0.5 * h * k2); k4 = f(e + h * k3)  # noqa: E702
        t, e = t + h, e + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
    return t


@pytest.mark.parametrize("k, alpha, e0", [(0.28, 0.8, 160.0), (2.0, 0.5, 0.3), (1.0, 0.8, 0.14)])
def test_scalar_finite_time_channel_settles_at_the_lemma_time(k, alpha, e0):
    T = e0 ** (1 - alpha) / (k * (1 - alpha))
    assert _settling_time(k, alpha, e0, T / 20000) == pytest.approx(T, rel=0.01)


def test_two_dimensional_settling_time_respects_the_lemma_bound():
    """e_i' = -k_i sig(e_i)^alpha, V = (e1^2 + e2^2)/2: V' <= -c V^a with a = (1+alpha)/2,
    c = min k * 2^a; the measured settling time (both channels at 0) is <= V0^(1-a) / (c (1-a))."""
    k, alpha, e0 = np.array([0.5, 2.0]), 0.8, np.array([1.5, -0.7])
    a = (1 + alpha) / 2
    c = k.min() * 2 ** a
    V0 = 0.5 * e0 @ e0
    bound = V0 ** (1 - a) / (c * (1 - a))
    settle = max(_settling_time(k[i], alpha, abs(e0[i]), 1e-4) for i in range(2))
    assert settle <= bound
    # and V' <= -c V^a holds along the way (checked at sampled states)
    for s in np.linspace(0.0, 1.0, 21)[:-1]:
        e = e0 * (1 - s)
        V_dot = -np.sum(k * np.abs(e) ** (1 + alpha))
        assert V_dot <= -c * (0.5 * e @ e) ** a + 1e-15


# ----------------------------------------------------------------------------- the z dynamics of theorem 1

P = law.paper_params(theorem=1, force_max=1e6, torque_max=1e6)


def _desired(tau):
    """A smooth desired trajectory with analytic derivatives: (value, rate, acceleration), each 6."""
    rho = (120 + 3 * math.sin(0.2 * tau), 0.6 * math.cos(0.2 * tau), -0.12 * math.sin(0.2 * tau))
    eps = (0.1 + 0.05 * math.sin(0.3 * tau), 0.015 * math.cos(0.3 * tau), -0.0045 * math.sin(0.3 * tau))
    beta = (-0.4 + 0.02 * tau, 0.02, 0.0)
    phi = (0.05 * math.sin(0.5 * tau), 0.025 * math.cos(0.5 * tau), -0.0125 * math.sin(0.5 * tau))
    theta = (0.1 * math.cos(0.4 * tau), -0.04 * math.sin(0.4 * tau), -0.016 * math.cos(0.4 * tau))
    psi = (0.3 + 0.1 * math.sin(0.2 * tau), 0.02 * math.cos(0.2 * tau), -0.004 * math.sin(0.2 * tau))
    return tuple(np.array(x) for x in zip(rho, eps, beta, phi, theta, psi))


def _measurement(s, tau):
    """s = [r (target - chaser, inertial) 3, v 3, Euler 3, omega 3]."""
    angles, rates, _ = los_kinematics(s[0:3], s[3:6])
    d, dd, ddd = _desired(tau)
    return LosMeasurement(angles, rates, s[6:9].copy(), s[9:12].copy(), d[:3], dd[:3], ddd[:3], d[3:], dd[3:], ddd[3:])


def _nominal_rates(s, force_b, torque):
    """The continuous nominal model, written independently of the law's F and G: inertial relative motion
    r'' = -C_ib F / m_n (no f, no gravity difference), Theta' = R^-1 omega, J_n omega' = T - omega x J_n omega."""
    J = np.asarray(P.inertia)
    C_ib = dcm_from_euler312(s[6:9]).T
    w = s[9:12]
    return np.concatenate([s[3:6], -C_ib @ force_b / P.mass, euler312_rate_matrix_inverse(s[6], s[7]) @ w,
                           (torque - np.cross(w, J * w)) / J])


def _flow(s, span, force_b, torque, steps=20):
    h = span / steps
    for _ in range(steps):
        k1 = _nominal_rates(s, force_b, torque)
        k2 = _nominal_rates(s + 0.5 * h * k1, force_b, torque)
        k3 = _nominal_rates(s + 0.5 * h * k2, force_b, torque)
        k4 = _nominal_rates(s + h * k3, force_b, torque)
        s = s + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
    return s


def _state_at(tau0):
    """A state whose errors are all outside the guard Delta (eta is then the exact derivative gain)."""
    d, dd, _ = _desired(tau0)
    rho, eps, beta = d[0] + 20.0, d[1] + 0.05, d[2] - 0.04
    r = rho * los_frame(eps, beta)[0]
    # relative velocity from chosen LOS rates: r' = rho' x_l + rho (omega_l x x_l), built numerically
    rates = dd[:3] + [0.8, -0.002, 0.003]
    h = 1e-6
    r_p = (rho + h * rates[0]) * los_frame(eps + h * rates[1], beta + h * rates[2])[0]
    r_m = (rho - h * rates[0]) * los_frame(eps - h * rates[1], beta - h * rates[2])[0]
    v = (r_p - r_m) / (2 * h)
    euler = d[3:] + [0.06, -0.05, 0.07]
    omega = np.array([0.01, -0.02, 0.03])
    return np.concatenate([r, v, euler, omega])


def test_theorem1_z_dynamics_close_as_designed():
    """With w = 0 (nominal model, theta_hat = 0) and no limits, the commanded force and torque held at t0
    give z' = -A^T e1 - K2 sig(z)^alpha - K3 sgn(z) (central difference of z along the continuous model)."""
    tau0, h = 37.0, 1e-3
    s0 = _state_at(tau0)
    m0 = _measurement(s0, tau0)
    out, _ = law.step(P, law.initial_state(P), m0)
    assert out.status & ~law.STATUS_WEIGHT_BOUND == law.STATUS_OK     # no limit acted on this step's output
    terms = law.tracking_terms(P, m0)
    assert np.all(np.abs(terms.e1) > P.delta)
    z_plus = law.tracking_terms(P, _measurement(_flow(s0, h, out.force, out.torque), tau0 + h)).z
    z_minus = law.tracking_terms(P, _measurement(_flow(s0, -h, out.force, out.torque), tau0 - h)).z
    z_dot = (z_plus - z_minus) / (2 * h)
    At_e1 = np.concatenate([terms.e1[:3], euler312_rate_matrix_inverse(*m0.euler[:2]).T @ terms.e1[3:]])
    expected = -At_e1 - np.asarray(P.k2) * law.sig(terms.z, P.alpha) - P.k3 * np.sign(terms.z)
    np.testing.assert_allclose(z_dot, expected, rtol=1e-5, atol=1e-9)
    # teeth: without the cross term A^T e1 the same comparison fails
    assert np.max(np.abs(z_dot - (expected + At_e1))) > 1e-3


# ----------------------------------------------------------------------------- basis, weights, invalid input


def test_basis_is_the_gaussian_of_the_scaled_error():
    p = law.paper_params(nodes=5, sigma=0.8, centre_span=1.2)
    e1 = np.array([30.0, 0.1, -0.05, 0.02, 0.3, -0.1])
    e2 = np.array([-2.0, 0.01, 0.02, -0.05, 0.0, 0.08])
    e = np.concatenate([e1, e2]) / np.array(p.input_scale)
    centres = np.linspace(-p.centre_span, p.centre_span, p.nodes)
    expected = [math.exp(-sum((ei - c) ** 2 for ei in e) / (2 * p.sigma ** 2)) for c in centres]
    np.testing.assert_allclose(law.basis(p, e1, e2), expected, rtol=1e-14)


def test_weights_stay_within_their_bound_and_the_bound_is_reported():
    p = law.paper_params()
    phi = np.ones(p.nodes)
    z = np.array([50.0, -3.0, 0.001, 9.0, -9.0, 0.0])
    theta, hit = law.adapt(p, np.zeros((p.nodes, 6)), phi, z, p.gamma, 0.1)
    bound = np.array([0.1, 0.001, 0.001, 0.01, 0.01, 0.01])     # docs/rbf_paper002.toml
    assert hit
    np.testing.assert_array_equal(theta[0], np.clip(0.1 * z, -bound, bound))
    # a small update is the leaky Euler step, unclipped: (1 - T gamma lambda) theta + T gamma phi z
    theta2, hit2 = law.adapt(p, theta, 0.5 * phi, 1e-4 * np.ones(6), p.gamma, 0.1)
    assert not hit2
    np.testing.assert_allclose(theta2, (1 - 0.1 * p.lam) * theta + 0.1 * 0.5e-4, rtol=1e-15)


def test_the_second_network_sees_the_last_command():
    """Theorem 2's basis is phi_j times a Gaussian of the previous command: equal to phi_j when the
    command sits on the node's centre, smaller elsewhere; so theta_Delta learns apart from theta."""
    p = law.paper_params(theorem=2)
    phi = np.linspace(0.1, 0.9, p.nodes)
    c = p.centres()
    for j in range(p.nodes):
        on_centre = law.command_basis(p, phi, np.full(6, c[j]))
        assert on_centre[j] == phi[j]
        others = [k for k in range(p.nodes) if k != j]
        expected = phi[others] * np.exp(-6 * (c[j] - c[others]) ** 2 / (2 * p.sigma ** 2))
        np.testing.assert_allclose(on_centre[others], expected, rtol=1e-14)
    tau0 = 37.0
    m = _measurement(_state_at(tau0), tau0)
    state = law.initial_state(p)
    for _ in range(20):
        out, state = law.step(p, state, m)
    np.testing.assert_array_equal(state.command, np.concatenate([out.force / p.force_max, out.torque / p.torque_max]))
    assert np.max(np.abs(state.theta_delta - state.theta)) > 1e-3 * np.max(np.abs(state.theta))
    _, state1 = law.step(law.paper_params(theorem=1), law.initial_state(p), m)
    assert not np.any(state1.theta_delta)


def test_weights_never_leave_the_bound_over_saturated_steps():
    p = law.paper_params(theorem=2)
    tau0 = 37.0
    m = _measurement(_state_at(tau0), tau0)
    m = LosMeasurement(**{**m.__dict__, "los": m.los + [60.0, 0.0, 0.0]})   # 80 m out: large z, saturation
    state = law.initial_state(p)
    for _ in range(200):
        out, state = law.step(p, state, m)
    assert out.status & law.STATUS_WEIGHT_BOUND and out.status & law.STATUS_FORCE_LIMITED
    for w in (state.theta, state.theta_delta):
        assert np.all(np.abs(w) <= np.array(p.theta_max))
    assert np.max(np.abs(out.force)) == p.force_max


@pytest.mark.parametrize("field, index, value", [
    ("los", 0, float("nan")), ("omega", 2, float("inf")), ("los", 0, 0.5), ("los", 1, 1.3),
    ("euler", 1, 3.6), ("los_rate", 0, 150.0), ("euler_d_rate", 0, 1.5), ("los_d_acc", 2, 11.0)])
def test_invalid_input_gives_zero_output_and_leaves_the_weights(field, index, value):
    p = law.paper_params()
    tau0 = 37.0
    good = _measurement(_state_at(tau0), tau0)
    controller = law.RbfLaw(p)
    controller(good)                                   # non-zero weights
    before = controller.state
    assert np.any(before.theta != 0)
    bad_value = getattr(good, field).copy()
    bad_value[index] = value
    out = controller(LosMeasurement(**{**good.__dict__, field: bad_value}))
    assert out.status == law.STATUS_INVALID_INPUT
    assert not np.any(out.force) and not np.any(out.torque) and not np.any(out.w_hat)
    assert controller.state.theta is before.theta and controller.state.theta_delta is before.theta_delta
    assert np.any(before.command != 0) and not np.any(controller.state.command)   # the command sent was 0


def test_wrapped_angle_differences():
    np.testing.assert_allclose(law.wrap_difference([3.0 - (-3.0), -3.2 - 3.1, 0.5]),
                               [6.0 - 2 * math.pi, -6.3 + 2 * math.pi, 0.5], atol=1e-15)


def test_a_wrapped_difference_reaches_the_step():
    """q_beta = 3.4 against q_beta_d = -3.4 is 6.8 - 2 pi apart, not 6.8 (and likewise theta, psi)."""
    tau0 = 37.0
    m = _measurement(_state_at(tau0), tau0)
    m = LosMeasurement(**{**m.__dict__, "los": np.array([m.los[0], m.los[1], 3.4]),
                          "los_d": np.array([m.los_d[0], m.los_d[1], -3.4]),
                          "euler": np.array([m.euler[0], -3.3, 3.45]), "euler_d": np.array([m.euler_d[0], 3.3, -3.45])})
    e1 = law.tracking_terms(law.paper_params(), m).e1
    np.testing.assert_allclose(e1[[2, 4, 5]], [6.8 - 2 * math.pi, -6.6 + 2 * math.pi, 6.9 - 2 * math.pi], rtol=1e-12)


@pytest.mark.parametrize("params", [law.paper_params(), law.paper_params(theorem=1), example_params()],
                         ids=["paper", "theorem1", "example"])
def test_the_float64_law_and_the_flight_units_golden_model_agree(params):
    """On the unit's gate rows (inside and edges: random weights, commands, box edges) the float64 law and
    the float32 golden model give the same status and, within float32 rounding, the same outputs and new
    state (relative to the output limits and weight bounds)."""
    unit = RbfUnit(params, 0.1)
    bound = np.asarray(params.theta_max)
    for name in ("inside", "edges"):
        batch = unit.gate_classes(600, seed=3)[name]
        out32, state32 = unit.golden(batch.state, batch.input)
        for i in range(len(batch.input)):
            s = batch.state[i]
            state = law.RbfState(s["theta"].reshape(-1, 6).astype(float), s["theta_delta"].reshape(-1, 6).astype(float),
                                 s["command"].astype(float))
            out, new = law.step(params, state, from_record(batch.input[i:i + 1]), 0.1)
            o = out32[i]
            assert out.status == o["status"], (name, i, out.status, o["status"])
            pairs = {"force": (out.force, o["force"], 1e-4 * params.force_max),
                     "torque": (out.torque, o["torque"], 1e-4 * params.torque_max),
                     "w_hat": (out.w_hat, o["w_hat"], 1e-5 * params.nodes * bound),
                     "theta": (new.theta, state32[i]["theta"].reshape(-1, 6), 1e-5 * bound),
                     "theta_delta": (new.theta_delta, state32[i]["theta_delta"].reshape(-1, 6), 1e-5 * bound),
                     "command": (new.command, state32[i]["command"], 1e-4)}
            for field, (ours, theirs, tol) in pairs.items():
                worst = float(np.max(np.abs(ours - theirs) / tol))
                assert worst <= 1.0, (name, i, field, worst)
