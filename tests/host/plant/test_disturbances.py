"""Disturbance torques and their environment models against independent formulas and published values."""
import numpy as np

from host.core import rotations as rot
from host.core.constants import DEG, MU_EARTH, WGS84_A
from host.plant.disturbances import (DEFAULT_DISTURBANCES, DisturbanceParams, aerodynamic_torque,
                               gravity_gradient_torque, magnetic_torque, solar_radiation_torque)
from host.plant.earth import ecef_to_eci, eci_to_ecef
from host.plant.environment import (AU, EARTH_RADIUS_DIPOLE, IGRF2015_DIPOLE_NT, air_density,
                              magnetic_field_eci, sun_position_eci, sunlit_fraction)
from host.gnc.guidance import desired_state
from host.sim.simulator import environment_track
from host.plant.spacecraft import TABLE6_INERTIA
from host.sim.targets import central_target
from host.core.timebase import utc_to_jd

RNG = np.random.default_rng(3)


def test_gravity_gradient_matches_the_formula_evaluated_in_inertial_axes():
    # independent path: rotate the inertia to S_i, take 3mu/r^3 R^ x (I_i R^) there, rotate back
    for _ in range(20):
        L_bi = rot.dcm_from_quat(rot.quat_normalise(RNG.normal(size=4)))
        R = RNG.normal(size=3)
        R *= RNG.uniform(6.7e6, 7.2e6) / np.linalg.norm(R)
        r = np.linalg.norm(R)
        I_i = L_bi.T @ TABLE6_INERTIA @ L_bi
        expected_i = 3 * MU_EARTH / r**3 * np.cross(R / r, I_i @ (R / r))
        np.testing.assert_allclose(gravity_gradient_torque(R, L_bi, TABLE6_INERTIA), L_bi @ expected_i,
                                   rtol=1e-12, atol=1e-18)


def test_gravity_gradient_pitch_torque_closed_form():
    # diagonal inertia, nadir tilted by a about body x: T_x = 3mu/r^3 (Iz - Iy) sin a cos a
    I = np.diag([100.0, 200.0, 350.0])
    a, r = 0.3, 7.0e6
    R_b = r * np.array([0.0, np.sin(a), np.cos(a)])
    T = gravity_gradient_torque(R_b, np.eye(3), I)
    np.testing.assert_allclose(T, [3 * MU_EARTH / r**3 * 150.0 * np.sin(a) * np.cos(a), 0, 0], rtol=1e-13)
    # a principal axis along the radius feels no torque
    np.testing.assert_allclose(gravity_gradient_torque([0, 0, r], np.eye(3), I), 0.0, atol=1e-20)


def test_sun_ephemeris_matches_vallado_example_5_1():
    # Vallado, Fundamentals of Astrodynamics, Example 5-1: 2006-04-02 00:00 UT1
    r = sun_position_eci(*utc_to_jd(2006, 4, 2)) / AU
    np.testing.assert_allclose(r, [0.9771945, 0.1924424, 0.0834308], atol=5e-6)


def test_sun_declination_at_the_june_2017_solstice_is_the_obliquity():
    r = sun_position_eci(*utc_to_jd(2017, 6, 21, 4, 24))   # solstice 2017-06-21 04:24 UTC
    assert abs(np.degrees(np.arcsin(r[2] / np.linalg.norm(r))) - 23.437) < 0.01


def test_cylindrical_shadow():
    s = np.array([AU, 0, 0])
    assert sunlit_fraction([-7e6, 0, 0], s) == 0.0           # behind the Earth
    assert sunlit_fraction([7e6, 0, 0], s) == 1.0            # sun side
    assert sunlit_fraction([-7e6, 0, WGS84_A + 1e3], s) == 1.0  # behind but above the cylinder


def test_dipole_field_is_minus_gradient_of_the_igrf_degree1_potential():
    # V = a^3 (m . r)/r^3 (nT m), B = -grad V, evaluated in ECEF by central differences
    jd, sec = utc_to_jd(2017, 5, 31, 4, 40)
    m = IGRF2015_DIPOLE_NT * 1e-9
    a = EARTH_RADIUS_DIPOLE

    def V(r):
        return a**3 * (m @ r) / np.linalg.norm(r) ** 3

    for _ in range(5):
        r_e = RNG.normal(size=3)
        r_e *= 6.9e6 / np.linalg.norm(r_e)
        h = 1.0
        grad = np.array([(V(r_e + h * e) - V(r_e - h * e)) / (2 * h) for e in np.eye(3)])
        r_i = ecef_to_eci(r_e, jd, sec)   # the same point in ECI at that time
        B_e = eci_to_ecef(magnetic_field_eci(r_i, jd, sec), jd, sec)
        np.testing.assert_allclose(B_e, -grad, rtol=1e-6, atol=1e-12)
    # field strength at 500 km: 20-60 microtesla
    assert 1.5e-5 < np.linalg.norm(B_e) < 6e-5


def test_exponential_atmosphere_table_values():
    assert np.isclose(air_density(500e3), 6.967e-13, rtol=1e-12)
    assert np.isclose(air_density(550e3), 6.967e-13 * np.exp(-50 / 63.822), rtol=1e-12)


def test_aero_srp_magnetic_torques_are_offset_cross_force():
    p = DisturbanceParams(drag_cp_offset=np.array([0, 0, 0.5]), srp_cp_offset=np.array([0, 0.4, 0]),
                          residual_dipole=np.array([2.0, 0, 0]))
    v = np.array([7600.0, 0, 0])
    # drag along -x at the cp +0.5 z: torque = r x F = 0.5 z x (-F x) = -0.5 F y
    F = 0.5 * 1e-12 * p.drag_coefficient * p.drag_area * 7600.0**2
    np.testing.assert_allclose(aerodynamic_torque(1e-12, v, np.eye(3), p), [0, -0.5 * F, 0], rtol=1e-12)
    Fs = 4.56e-6 * p.srp_area * (1 + p.srp_reflectivity)
    np.testing.assert_allclose(solar_radiation_torque([1.0, 0, 0], 1.0, np.eye(3), p), [0, 0, 0.4 * Fs], rtol=1e-12)
    assert np.all(solar_radiation_torque([1.0, 0, 0], 0.0, np.eye(3), p) == 0)
    np.testing.assert_allclose(magnetic_torque([0, 3e-5, 0], np.eye(3), p), [0, 0, 6e-5], rtol=1e-12)


def test_magnitudes_along_the_central_target_pass():
    env = environment_track(1001, 0.1)
    tg = central_target()
    d = desired_state(env.jd_days, env.sec_of_day, env.R, env.V, tg.lon, tg.lat)
    p = DEFAULT_DISTURBANCES
    peak = np.zeros(4)
    for k in range(0, len(env), 20):
        L = d.L_di[k]
        torques = [gravity_gradient_torque(env.R[k], L, TABLE6_INERTIA),
                   aerodynamic_torque(env.rho[k], env.v_rel[k], L, p),
                   solar_radiation_torque(env.sun_dir[k], env.sunlit[k], L, p),
                   magnetic_torque(env.B[k], L, p)]
        peak = np.maximum(peak, [np.linalg.norm(t) for t in torques])
    assert np.all(peak >= 1e-5) and np.all(peak <= 1e-3), peak
    assert env.sunlit.min() == 1.0  # the pass over China at 12:40 local time is sunlit
    assert 450e3 < np.linalg.norm(env.R[0]) - WGS84_A < 550e3
    assert abs(tg.lat / DEG - 30) < 1e-12
