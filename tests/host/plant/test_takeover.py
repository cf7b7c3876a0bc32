"""Paper 004's takeover truth: J_c against an independent two-shift parallel-axis computation, the error
quaternion against the DCM path, angular-momentum conservation with the wheels only exchanging momentum,
the counter-torque's sign and saturation, and the identity of section 2 on the truth."""
import numpy as np
import pytest

from host.core.constants import DEG
from host.core.rotations import dcm_from_quat, quat_from_dcm
from host.errors import HostError
from host.plant import takeover as tk
from host.plant.spacecraft import TABLE6_INERTIA


def _shift(J, m, a):
    """Steiner: the inertia of a body of mass m about a point at -a from its CoM."""
    a = np.asarray(a, float)
    return J + m * (np.dot(a, a) * np.eye(3) - np.outer(a, a))


def test_combined_inertia_equals_two_parallel_axis_shifts_to_the_common_com():
    m_s, m_t = tk.SERVICER_MASS, tk.TARGET_MASS
    r = tk.COM_OFFSET
    com = m_t * r / (m_s + m_t)                       # from the servicer's CoM
    c, s = np.cos(30 * DEG), np.sin(30 * DEG)
    R = np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]])  # target axes -> servicer axes, 30 deg about z
    J_t = R @ np.diag([150.0, 120.0, 100.0]) @ R.T
    expected = _shift(TABLE6_INERTIA, m_s, -com) + _shift(J_t, m_t, r - com)
    J_c = tk.combined_inertia(TABLE6_INERTIA, m_s, tk.TARGET_INERTIA, m_t, tk.TARGET_ROTATION, r)
    np.testing.assert_allclose(J_c, expected, rtol=1e-12)
    np.testing.assert_allclose(tk.TakeoverPlant().inertia, J_c)
    # the doc's rounded table (section 1)
    np.testing.assert_allclose(J_c, [[969.8, -174.4, 90.3], [-174.4, 1883.9, 3.3], [90.3, 3.3, 2355.6]],
                               atol=0.06)


def test_combined_inertia_refuses_non_positive_masses():
    with pytest.raises(HostError):
        tk.combined_inertia(TABLE6_INERTIA, 1000.0, tk.TARGET_INERTIA, 0.0, np.eye(3), tk.COM_OFFSET)


def test_error_quaternion_is_the_one_of_the_dcm_product():
    rng = np.random.default_rng(3)
    for _ in range(20):
        q, q_ref = (v / np.linalg.norm(v) for v in rng.normal(size=(2, 4)))
        L = dcm_from_quat(q) @ dcm_from_quat(q_ref).T
        np.testing.assert_allclose(tk.error_quat(q, q_ref), quat_from_dcm(L), atol=1e-12)


def test_capture_state_is_twenty_degrees_about_the_doc_axis():
    x = tk.capture_state(tk.TakeoverPlant())
    assert 2 * np.arccos(x[3]) == pytest.approx(20 * DEG, abs=1e-12)
    np.testing.assert_allclose(x[0:3] / np.linalg.norm(x[0:3]), [0.6, -0.48, 0.64], atol=1e-12)
    np.testing.assert_allclose(x[4:7], np.array([0.3, -0.5, 0.4]) * DEG)


def test_wheels_only_exchange_momentum_without_counter_torque():
    """Zero counter-torque (kp = kd = 0) and a wheel torque profile: the inertial H = C(q)ᵀ(J_c ω + h_w)
    is constant; and with zero command the wheel momentum does not change."""
    plant = tk.TakeoverPlant(kp=0.0, kd=0.0)
    x = tk.capture_state(plant, h_w0=(3.0, -2.0, 1.0))
    H0 = dcm_from_quat(x[0:4]).T @ (plant.inertia @ x[4:7] + x[7:10])
    hw0 = x[7:10].copy()
    for k in range(100):
        x = plant.hold(x, np.zeros(3))
    np.testing.assert_array_equal(x[7:10], hw0)
    for k in range(100):
        x = plant.hold(x, 0.5 * np.array([np.sin(0.1 * k), np.cos(0.07 * k), -0.3]))
    H = dcm_from_quat(x[0:4]).T @ (plant.inertia @ x[4:7] + x[7:10])
    assert np.linalg.norm(H - H0) < 1e-9 * np.linalg.norm(H0)
    assert np.linalg.norm(x[7:10] - hw0) > 1.0            # the wheels did take momentum


def test_counter_torque_opposes_the_deviation_and_saturates():
    q_t0 = tk.axis_angle_quat([0.6, -0.48, 0.64], 20 * DEG)
    # small deviation about x from the capture pointing, at rest: the torque points back (negative x)
    q = tk.quat_compose(tk.axis_angle_quat([1, 0, 0], 2 * DEG), q_t0)
    tau = tk.counter_torque(q, np.zeros(3), q_t0)
    np.testing.assert_allclose(tau, [-0.5 * np.sin(1 * DEG), 0, 0], atol=1e-15)
    # a rate: damping opposes it
    tau = tk.counter_torque(q_t0, np.array([0.0, 0.004, 0.0]), q_t0)
    np.testing.assert_allclose(tau, [0, -0.02, 0], atol=1e-15)
    # large deviation and rate: each axis clipped at 0.1 N·m, with the opposing sign
    q = tk.quat_compose(tk.axis_angle_quat([1, -1, 1], 90 * DEG), q_t0)
    tau = tk.counter_torque(q, np.array([0.1, -0.1, 0.1]), q_t0)
    np.testing.assert_allclose(tau, [-0.1, 0.1, -0.1])
    # the power the target puts into a pure rate is negative (it brakes)
    w = np.array([0.01, -0.02, 0.005])
    assert tk.counter_torque(q_t0, w, q_t0) @ w < 0


def test_unknown_term_identity_on_the_truth():
    """d = −ΔJ ω̇ − ω×(ΔJ ω) + τ_t (truth) equals J_s ω̇ + ω×(J_s ω + h_w) − u (measurable), with ω̇ the
    truth's own derivative, at random states and commands."""
    plant = tk.TakeoverPlant()
    rng = np.random.default_rng(7)
    for _ in range(20):
        q = rng.normal(size=4)
        x = np.concatenate([q / np.linalg.norm(q), rng.uniform(-0.02, 0.02, 3), rng.uniform(-40, 40, 3)])
        u = rng.uniform(-1, 1, 3)
        wdot = plant.derivative(x, u)[4:7]
        d_truth = plant.unknown_term(x, wdot)
        d_meas = tk.measured_unknown_term(TABLE6_INERTIA, x[4:7], wdot, x[7:10], u)
        np.testing.assert_allclose(d_truth, d_meas, atol=1e-12)
        # and the derivative really is J_c⁻¹ (u + τ_t − ω×(J_c ω + h_w)): compare J_c ω̇ directly
        w, hw = x[4:7], x[7:10]
        rhs = u + plant.counter_torque(x) - np.cross(w, plant.inertia @ w + hw)
        np.testing.assert_allclose(plant.inertia @ wdot, rhs, atol=1e-12)


def test_momentum_limit_blocks_only_spin_up():
    plant = tk.TakeoverPlant()
    u = plant.applied_torque([2.0, -0.3, 0.4], np.array([-50.0, 50.0, 10.0]))
    # x: ḣ = −u = −1 would push h from −50 to beyond; y: ḣ = +0.3 beyond +50; z: free
    np.testing.assert_allclose(u, [0.0, 0.0, 0.4])
    u = plant.applied_torque([-2.0, 0.3, 0.4], np.array([-50.0, 50.0, 10.0]))
    np.testing.assert_allclose(u, [-1.0, 0.3, 0.4])


def test_rk4_at_the_plant_step_matches_a_ten_times_finer_step():
    """10 s of the tumbling body fighting the target, with a held wheel torque: 0.01 s against 0.001 s."""
    plant = tk.TakeoverPlant()
    x0 = tk.capture_state(plant, omega0=np.array([1.0, -2.0, 1.5]) * DEG)
    u = np.array([0.3, -0.5, 0.2])
    coarse, fine = x0.copy(), x0.copy()
    for _ in range(100):
        coarse = plant.hold(coarse, u, 0.1, 0.01)
        fine = plant.hold(fine, u, 0.1, 0.001)
    np.testing.assert_allclose(coarse, fine, atol=1e-9)
