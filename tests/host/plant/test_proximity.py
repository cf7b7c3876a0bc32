"""Paper 002's proximity truth: actuator D(u) against its definition, the target tumble against its spin
definition, the chaser's rigid-body and thrust conventions against conservation laws and rotations."""
import math

import numpy as np

from host.core.constants import DEG, MU_EARTH
from host.core.rotations import dcm_from_quat, skew
from host.plant import proximity as px


def test_dead_zone_saturation_matches_its_definition():
    u = np.array([-300.0, -200.0, -150.0, -1.0, -0.999, 0.0, 0.5, 1.0, 50.0, 200.0, 250.0])
    expected = np.array([-200.0, -200.0, -150.0, -1.0, 0.0, 0.0, 0.0, 1.0, 50.0, 200.0, 200.0])
    np.testing.assert_array_equal(px.dead_zone_saturation(u, 1.0, 200.0), expected)
    # odd in u: D(-u) = -D(u)
    np.testing.assert_array_equal(px.dead_zone_saturation(-u, 1.0, 200.0), -expected)


def test_actuators_apply_thrust_and_torque_limits_per_axis():
    force, torque = px.Actuators().apply([0.9, -3.0, 1e4], [0.004, -0.2, -7.0])
    np.testing.assert_array_equal(force, [0.0, -3.0, 200.0])
    np.testing.assert_array_equal(torque, [0.0, -0.2, -0.5])


def test_target_tumble_is_a_constant_spin_about_an_axis_20deg_from_y():
    tumble = px.TargetTumble()
    w = tumble.rate_vector()
    assert abs(math.degrees(math.acos(w[1] / np.linalg.norm(w))) - 20.0) < 1e-12
    assert abs(np.linalg.norm(w) - 0.5 * DEG) < 1e-18
    for t in (0.0, 123.4, 900.0):
        C = tumble.dcm(t)
        np.testing.assert_allclose(C @ C.T, np.eye(3), atol=1e-14)
        assert abs(np.linalg.det(C) - 1.0) < 1e-14
        # body -> inertial columns rotate with w: C' = [w]x C (central differences)
        h = 1e-3
        C_dot = (tumble.dcm(t + h) - tumble.dcm(t - h)) / (2 * h)
        np.testing.assert_allclose(C_dot, skew(w) @ C, atol=1e-11)
        # the spin axis is the body y axis, the feature (body x) is perpendicular to it
        np.testing.assert_allclose(C[:, 1], w / np.linalg.norm(w), atol=1e-14)
        assert abs(tumble.feature(t) @ w) < 1e-15


def test_manoeuvre_has_the_step_at_400s():
    before, after = px.target_manoeuvre(400.0 - 1e-9), px.target_manoeuvre(400.0)
    assert abs((after[0] - before[0]) - 0.005) < 1e-9
    np.testing.assert_allclose(px.target_manoeuvre(0.0), [0.0, 0.008, 0.006 * math.sin(1.0)], atol=0)


def _free_state(omega):
    q = np.array([0.1, -0.3, 0.2, 0.9])
    q /= np.linalg.norm(q)
    target = px.circular_orbit_state()
    return [*target, *(target[:3] + [50.0, -20.0, 10.0]), *target[3:], *q, *omega]


def test_torque_free_chaser_conserves_inertial_angular_momentum_and_energy():
    plant = px.ProximityPlant()
    J = np.diag(plant.inertia)
    y = _free_state([0.2, -0.1, 0.15])
    def momentum(y):
        return dcm_from_quat(y[12:16]).T @ (J @ np.asarray(y[16:19]))    # C_ib J w
    h0, e0 = momentum(y), 0.5 * np.asarray(y[16:19]) @ J @ np.asarray(y[16:19])
    for k in range(1000):                                               # 10 s at 0.01 s
        y = plant.rk4_step(0.01 * k, y, 0.01, (0.0, 0.0, 0.0), (0.0, 0.0, 0.0))
    np.testing.assert_allclose(momentum(y), h0, atol=1e-10)
    assert abs(0.5 * np.asarray(y[16:19]) @ J @ np.asarray(y[16:19]) - e0) < 1e-11
    assert np.linalg.norm(np.asarray(y[16:19]) - [0.2, -0.1, 0.15]) > 1e-3      # it did precess


def test_body_thrust_acts_along_the_body_axis_in_inertial_space():
    plant = px.ProximityPlant()
    y = _free_state([0.0, 0.0, 0.0])
    C_bi = dcm_from_quat(y[12:16])
    force = np.array([9.5, -19.0, 4.75])
    with_thrust = np.asarray(plant.rates(3.0, y, tuple(force), (0, 0, 0)))
    without = np.asarray(plant.rates(3.0, y, (0, 0, 0), (0, 0, 0)))
    np.testing.assert_allclose(with_thrust[9:12] - without[9:12], C_bi.T @ force / 95.0, atol=1e-15)
    np.testing.assert_array_equal(with_thrust[3:6], without[3:6])        # the target does not feel it


def test_target_stays_on_its_circular_orbit():
    plant = px.ProximityPlant(manoeuvre=lambda t: (0.0, 0.0, 0.0))
    y = _free_state([0.0, 0.0, 0.0])
    y = plant.hold(0.0, y, 600.0, 1.0, (0, 0, 0), (0, 0, 0))
    r = np.asarray(y[0:3])
    assert abs(np.linalg.norm(r) - px.TARGET_RADIUS) < 1e-3
    # the angle swept is n t
    n = math.sqrt(MU_EARTH / px.TARGET_RADIUS ** 3)
    assert abs(math.acos(r[0] / np.linalg.norm(r)) - n * 600.0) < 1e-9
