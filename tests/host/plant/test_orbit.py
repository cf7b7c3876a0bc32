"""Two-body orbit: Keplerian -> ECI against textbook worked examples, RK4 invariants and order,
the Table 5 orbit against the circular-orbit formulas."""
import numpy as np
import pytest

from host.core.constants import MU_EARTH
from host.plant.orbit import (
    TABLE5_ELEMENTS, TABLE5_EPOCH, KeplerianElements, angular_momentum, conic_to_eci, kepler_state,
    keplerian_to_eci, mean_motion, propagate_rk4, specific_energy, state_from_elements,
    table5_initial_state,
)

D = np.pi / 180.0


def test_curtis_example_4_7():
    # Curtis, Orbital Mechanics for Engineering Students, Example 4.7 (mu = 398600 km^3/s^2):
    # h = 80000 km^2/s, e = 1.4, i = 30, RAAN = 40, argp = 60, theta = 30 deg
    mu = 398600.0
    R, V = conic_to_eci(80000.0**2 / mu, 1.4, 30 * D, 40 * D, 60 * D, 30 * D, mu)
    # printed to 4 significant figures
    np.testing.assert_allclose(R, [-4040.0, 4815.0, 3629.0], rtol=0, atol=0.5)
    np.testing.assert_allclose(V[0], -10.39, rtol=0, atol=0.005)
    np.testing.assert_allclose(V[1:], [-4.772, 1.744], rtol=0, atol=0.0005)


def test_vallado_example_2_6():
    # Vallado, Fundamentals of Astrodynamics and Applications (4th ed.), Example 2-6 (COE2RV)
    R, V = conic_to_eci(11067.790, 0.83285, 87.87 * D, 227.89 * D, 53.38 * D, 92.335 * D, 398600.4418)
    np.testing.assert_allclose(R, [6525.368, 6861.532, 6449.119], rtol=0, atol=1e-3)
    np.testing.assert_allclose(V, [4.902279, 5.533140, -1.975710], rtol=0, atol=2e-6)


def test_table5_orbit_is_the_stated_circular_orbit():
    el = TABLE5_ELEMENTS
    R, V = keplerian_to_eci(el)
    a, i, raan, u = 6878.14e3, 97.3 * D, 255.0 * D, 145.0 * D
    # circular orbit, argument of latitude u (textbook, e.g. Wertz): r = a * [...]
    expected = a * np.array([
        np.cos(raan) * np.cos(u) - np.sin(raan) * np.sin(u) * np.cos(i),
        np.sin(raan) * np.cos(u) + np.cos(raan) * np.sin(u) * np.cos(i),
        np.sin(u) * np.sin(i),
    ])
    np.testing.assert_allclose(R, expected, rtol=0, atol=1e-6)
    assert abs(np.linalg.norm(R) - a) < 1e-6
    assert abs(R @ V) / (a * np.linalg.norm(V)) < 1e-15
    assert abs(np.linalg.norm(V) - np.sqrt(MU_EARTH / a)) < 1e-9
    h = np.cross(R, V)
    assert abs(np.arccos(h[2] / np.linalg.norm(h)) - i) < 1e-14
    node = np.cross([0.0, 0.0, 1.0], h)
    assert abs(np.mod(np.arctan2(node[1], node[0]), 2 * np.pi) - raan) < 1e-14
    assert TABLE5_EPOCH == (2457905, 16800.0)  # JD 2457904.5 at 2017-05-31 0h UTC, + 4 h 40 min


@pytest.mark.parametrize("dt, tol_energy, tol_pos", [(10.0, 1e-10, 0.05), (1.0, 1e-13, 1e-5)])
def test_rk4_conserves_energy_and_momentum_over_one_orbit(dt, tol_energy, tol_pos):
    x0 = table5_initial_state()
    n = int(round(2 * np.pi / mean_motion(TABLE5_ELEMENTS.a) / dt))
    X = propagate_rk4(x0, dt, n)
    E, H = specific_energy(X), angular_momentum(X)
    assert np.max(np.abs(E / E[0] - 1.0)) < tol_energy
    assert np.max(np.linalg.norm(H - H[0], axis=-1)) / np.linalg.norm(H[0]) < tol_energy
    truth = kepler_state(TABLE5_ELEMENTS, dt * np.arange(n + 1))
    assert np.max(np.linalg.norm(X[:, :3] - truth[:, :3], axis=-1)) < tol_pos


def test_rk4_is_fourth_order_on_an_eccentric_orbit():
    el = KeplerianElements(a=8000e3, e=0.2, inc=0.5, raan=1.0, argp=2.0, nu=0.3)
    x0, t_end = state_from_elements(el), 3000.0
    truth = kepler_state(el, t_end)
    err = [np.linalg.norm(propagate_rk4(x0, dt, int(t_end / dt))[-1, :3] - truth[:3]) for dt in (20.0, 10.0)]
    assert 12.0 < err[0] / err[1] < 20.0  # 2^4 = 16


def test_kepler_state_closes_after_one_period_and_matches_energy():
    el = KeplerianElements(a=7500e3, e=0.3, inc=1.0, raan=0.2, argp=0.7, nu=2.5)
    x0 = state_from_elements(el)
    period = 2 * np.pi * np.sqrt(el.a**3 / MU_EARTH)
    np.testing.assert_allclose(kepler_state(el, period), x0, rtol=0, atol=1e-5)
    X = kepler_state(el, np.linspace(0, period, 37))
    np.testing.assert_allclose(specific_energy(X), -MU_EARTH / (2 * el.a), rtol=1e-13)
