"""Staring guidance: boresight on target, S_d = S_o at nadir, omega_d / omegadot_d against finite
differences, quaternion kinematics (eq. 3) and the paper's n-step prediction (eq. 9-10)."""
import numpy as np
import pytest

from host.plant.earth import ecef_to_geodetic
from host.core.frames import L_oi, orbital_axes
from host.gnc.guidance import desired_state
from host.plant.orbit import TABLE5_ELEMENTS, TABLE5_EPOCH, kepler_state
from host.core.rotations import dcm_from_quat, quat_from_dcm, quat_normalise, quat_rate, vee
from host.core.timebase import add_seconds, gmst

D = np.pi / 180.0
LON, LAT = 120 * D, 30 * D
PASS_TIMES = np.arange(-250.0, 400.0, 3.7)  # s from the Table 5 epoch; target above the horizon


def state_at(t):
    """Exact two-body state (the solution RK4 approximates) and time tag, t s after the epoch."""
    X = kepler_state(TABLE5_ELEMENTS, t)
    return add_seconds(*TABLE5_EPOCH, t), X[..., :3], X[..., 3:]


RULES = ("orbit_normal", "along_track")


def desired_at(t, lon=LON, lat=LAT, height=0.0, rule="orbit_normal"):
    (J, S), R, V = state_at(t)
    return desired_state(J, S, R, V, lon, lat, height, second_axis=rule)


def target_eci_independent(J, S, lon, lat, h=0.0):
    """WGS-84 geodetic -> ECEF (textbook formula) rotated by GMST about z."""
    a, f = 6378137.0, 1 / 298.257223563
    e2 = f * (2 - f)
    n = a / np.sqrt(1 - e2 * np.sin(lat) ** 2)
    x, y, z = (n + h) * np.cos(lat) * np.cos(lon), (n + h) * np.cos(lat) * np.sin(lon), (n * (1 - e2) + h) * np.sin(lat)
    g = gmst(J, S)
    return np.stack([np.cos(g) * x - np.sin(g) * y, np.sin(g) * x + np.cos(g) * y, np.broadcast_to(z, g.shape)], -1)


@pytest.mark.parametrize("rule", RULES)
def test_boresight_on_target_when_body_follows_desired_attitude(rule):
    (J, S), R, V = state_at(PASS_TIMES)
    for h in (0.0, 1500.0):
        ds = desired_state(J, S, R, V, LON, LAT, h, second_axis=rule)
        q_bi = quat_from_dcm(ds.L_di)  # body frame = S_d, attitude carried as a quaternion
        z_b = dcm_from_quat(q_bi)[..., 2, :]  # body z in ECI components (row 3 of L_bi)
        los = target_eci_independent(J, S, LON, LAT, h) - R
        cosang = np.sum(z_b * los, -1) / np.linalg.norm(los, axis=-1)
        sinang = np.linalg.norm(np.cross(z_b, los), axis=-1) / np.linalg.norm(los, axis=-1)
        assert np.all(cosang > 0)
        assert np.max(np.arctan2(sinang, cosang)) <= 1e-9


@pytest.mark.parametrize("rule", RULES)
def test_desired_frame_is_orthonormal_and_obeys_its_second_axis_rule(rule):
    (J, S), R, V = state_at(PASS_TIMES)
    L = desired_state(J, S, R, V, LON, LAT, second_axis=rule).L_di
    np.testing.assert_allclose(L @ np.swapaxes(L, -1, -2), np.broadcast_to(np.eye(3), L.shape), rtol=0, atol=1e-14)
    np.testing.assert_allclose(np.linalg.det(L), 1.0, rtol=0, atol=1e-14)
    n = np.cross(R, V)
    n /= np.linalg.norm(n, axis=-1, keepdims=True)
    if rule == "orbit_normal":  # x_d perpendicular to the orbit normal
        assert np.max(np.abs(np.sum(L[:, 0] * n, -1))) < 1e-14
    else:  # y_d perpendicular to x_o (the along-track axis of S_o)
        assert np.max(np.abs(np.sum(L[:, 1] * orbital_axes(R, V)[0], -1))) < 1e-14
    # y_d stays close to y_o = -n (only the small cross-track look angle tilts it)
    assert np.all(np.sum(L[:, 1] * -n, -1) > 0.9)


@pytest.mark.parametrize("rule", RULES)
@pytest.mark.parametrize("t", [-200.0, 0.0, 77.0, 300.0])
def test_desired_frame_equals_orbital_frame_at_nadir(t, rule):
    (J, S), R, V = state_at(t)
    # point where the satellite-to-Earth-centre line pierces the WGS-84 ellipsoid
    a, b = 6378137.0, 6378137.0 * (1 - 1 / 298.257223563)
    g = gmst(J, S)
    r_e = np.array([np.cos(g) * R[0] + np.sin(g) * R[1], -np.sin(g) * R[0] + np.cos(g) * R[1], R[2]])
    p = r_e / np.sqrt((r_e[0] ** 2 + r_e[1] ** 2) / a**2 + r_e[2] ** 2 / b**2)
    lon, lat, h = ecef_to_geodetic(p)
    ds = desired_state(J, S, R, V, lon, lat, h, second_axis=rule)
    np.testing.assert_allclose(ds.L_di, L_oi(R, V), rtol=0, atol=1e-9)


@pytest.mark.parametrize("rule", RULES)
def test_omega_d_matches_finite_differences_of_the_desired_dcm(rule):
    h = 0.01  # central difference: truncation h^2/6 |L'''| ~ 1e-10 rad/s, round-off ~1e-14
    c, p, m = (desired_at(PASS_TIMES + d, rule=rule) for d in (0.0, h, -h))
    Ldot = (p.L_di - m.L_di) / (2 * h)
    omega_fd = vee(-Ldot @ np.swapaxes(c.L_di, -1, -2))  # [w x] = -L' L^T for passive L
    err = np.linalg.norm(omega_fd - c.omega_d, axis=-1) / np.linalg.norm(c.omega_d, axis=-1)
    assert np.max(err) < 1e-6


@pytest.mark.parametrize("rule", RULES)
def test_omegadot_d_matches_finite_differences_of_omega_d(rule):
    h = 0.01
    c, p, m = (desired_at(PASS_TIMES + d, rule=rule) for d in (0.0, h, -h))
    fd = (p.omega_d - m.omega_d) / (2 * h)
    scale = np.max(np.abs(c.omegadot_d), axis=0)  # per-axis peak over the pass
    assert np.max(np.abs(fd - c.omegadot_d) / scale) < 1e-6


@pytest.mark.parametrize("rule", RULES)
def test_quaternion_kinematics_with_omega_d_track_the_desired_frame(rule):
    # eq. 3 integrated with RK4 from q(L_di(t0)) using the analytic omega_d must stay on S_d
    t0, dt, n = -100.0, 0.1, 2000
    q = quat_from_dcm(desired_at(t0, rule=rule).L_di)
    W = desired_at(t0 + 0.5 * dt * np.arange(2 * n + 1), rule=rule).omega_d  # at every half step
    for k in range(n):
        w0, w1, w2 = W[2 * k], W[2 * k + 1], W[2 * k + 2]
        k1 = quat_rate(q, w0)
        k2 = quat_rate(q + dt / 2 * k1, w1)
        k3 = quat_rate(q + dt / 2 * k2, w1)
        k4 = quat_rate(q + dt * k3, w2)
        q = quat_normalise(q + dt / 6 * (k1 + 2 * k2 + 2 * k3 + k4))
    L_err = dcm_from_quat(q) @ desired_at(t0 + n * dt, rule=rule).L_di.T
    angle = np.arccos(np.clip((np.trace(L_err) - 1) / 2, -1, 1))
    assert angle < 1e-9


@pytest.mark.parametrize("rule", RULES)
def test_n_step_prediction_eq_10_agrees_within_its_truncation_error(rule):
    # eq. 9-10 with the sequence of true omega_d: (w(t + n tau) - w(t)) / (n tau) is a forward
    # difference; its error is (n tau / 2) w''(xi), bounded by the peak of |w''| on the window.
    tau, n, h = 0.1, 10, 0.01
    t = PASS_TIMES[(PASS_TIMES > -150) & (PASS_TIMES < 300)]
    c, ahead = desired_at(t, rule=rule), desired_at(t + n * tau, rule=rule)
    pred = (ahead.omega_d - c.omega_d) / (n * tau)
    win = t[:, None] + np.linspace(0, n * tau, 11)[None, :]
    wdd = (desired_at(win + h, rule=rule).omegadot_d - desired_at(win - h, rule=rule).omegadot_d) / (2 * h)
    bound = 0.5 * n * tau * np.max(np.abs(wdd), axis=1)
    err = np.abs(pred - c.omegadot_d)
    assert np.all(err <= bound * 1.01 + 1e-12)
    # and the leading term is what remains: error ~ (n tau / 2) w''(t)
    lead = 0.5 * n * tau * wdd[:, 0]
    big = np.abs(lead) > 0.2 * np.max(np.abs(lead))
    np.testing.assert_allclose(err[big], np.abs(lead[big]), rtol=0.1)


def inside_table_2(ds):
    """Per-sample flag: omega_d, omegadot_d inside the paper's Table 2 ranges."""
    w, wd = ds.omega_d / D, ds.omegadot_d / D
    ok_w = (np.abs(w[..., 0]) <= 0.1) & (w[..., 1] >= -1.2) & (w[..., 1] <= 0.0) & (np.abs(w[..., 2]) <= 0.05)
    return ok_w & np.all(np.abs(wd) <= np.array([0.005, 0.015, 0.005]), -1)


@pytest.mark.parametrize("rule", RULES)
def test_central_target_pass_stays_inside_the_table_2_envelope_for_the_first_300_s(rule):
    assert np.all(inside_table_2(desired_at(np.arange(0.0, 300.0 + 1e-9, 0.1), rule=rule)))


def test_all_100_targets_inside_table_2_only_with_the_along_track_rule():
    from host.sim.targets import staring_targets
    t = np.arange(0.0, 300.0 + 1e-9, 0.5)
    (J, S), R, V = state_at(t)
    outside = {rule: 0 for rule in RULES}
    for tg in staring_targets():
        for rule in RULES:
            ds = desired_state(J, S, R, V, tg.lon, tg.lat, second_axis=rule)
            outside[rule] += not np.all(inside_table_2(ds))
    assert outside["along_track"] == 0
    # orbit_normal: omega_dz ~ pitch rate x sin(cross-track look angle) reaches ~0.16 deg/s
    assert outside["orbit_normal"] > 30


def test_unknown_second_axis_rule_is_rejected():
    (J, S), R, V = state_at(0.0)
    with pytest.raises(ValueError):
        desired_state(J, S, R, V, LON, LAT, second_axis="sun")


def test_batch_and_single_calls_agree():
    (J, S), R, V = state_at(PASS_TIMES[:5])
    batch = desired_state(J, S, R, V, LON, LAT)
    for k in range(5):
        one = desired_state(int(J[k]), float(S[k]), R[k], V[k], LON, LAT)
        np.testing.assert_array_equal(one.L_di, batch.L_di[k])
        np.testing.assert_array_equal(one.omega_d, batch.omega_d[k])
        np.testing.assert_array_equal(one.omegadot_d, batch.omegadot_d[k])
