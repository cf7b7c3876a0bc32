"""The takeover laws built from the law's parameter file (docs/gp-takeover.md §5, §11): the artifact's
float64 predictor, `gp_law(params)` and `baseline_law(params)`. The artifact is a small numpy-only one
(codegen.units.gp.example, with its ω̇ coordinates of Z set to 0 so that the law, which evaluates the
GP at ω̇ = 0, can sit exactly on an inducing point); the expected values are written out here."""
from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from codegen.units.gp import artifact as gpa
from codegen.units.gp.example import example_arrays, example_params
from host.control import takeover_laws as tl

M = 6
J = np.array([[900.0, -20.0, 10.0], [-20.0, 400.0, 5.0], [10.0, 5.0, 700.0]])


def _arrays() -> gpa.GpArrays:
    a = example_arrays(m=M, seed=3)
    Z = 0.5 * a.Z
    Z[:, 6:] = 0.0                                   # the law's ω̇ = 0 lies on the inducing points
    R = np.stack([0.2 * np.eye(M) for _ in range(3)])  # posterior variance well below the prior at Z
    return dataclasses.replace(a, Z=Z, R=R)


@pytest.fixture(scope="module")
def params():
    a = _arrays()
    raw = a.Z * a.input_scale
    art = gpa.GpArtifact(arrays=a, envelope_min=raw.min(0), envelope_max=raw.max(0))
    return dataclasses.replace(example_params(), gp=art, k1=3.0, k1_bar=9.0, k2=50.0, k2_bar=130.0, torque_max=0.4,
                               inertia=tuple(tuple(r) for r in J.tolist()))


def gp_by_hand(a: gpa.GpArrays, x):
    """μ_k = m̃_kᵀ L⁻¹k, σ²_k = σ_f² + jitter − ‖L⁻¹k‖² + ‖R_kᵀ L⁻¹k‖² (whitened SVGP), raw units."""
    xs = np.asarray(x) / a.input_scale / a.lengthscale
    zs = a.Z / a.lengthscale
    k = a.outputscale * np.exp(-0.5 * np.sum((zs - xs) ** 2, axis=1))
    Kzz = a.outputscale * np.exp(-0.5 * np.sum((zs[:, None] - zs[None]) ** 2, axis=2)) + a.jitter * np.eye(len(zs))
    w = np.linalg.solve(np.linalg.cholesky(Kzz), k)
    mu = np.array([a.m[i] @ w for i in range(3)])
    var = np.array([a.outputscale + a.jitter - w @ w + np.sum((a.R[i].T @ w) ** 2) for i in range(3)])
    return mu * a.output_scale, var * a.output_scale ** 2


def quat_of(q_v):
    q_v = np.asarray(q_v, float)
    return np.concatenate([q_v, [np.sqrt(1.0 - q_v @ q_v)]])


def test_the_predictor_is_reference_predict_and_the_hand_formula(params):
    a = params.gp.arrays
    pred = tl.ArtifactPredictor(a)
    rng = np.random.default_rng(1)
    for x in rng.normal(0.0, 1.0, (5, 9)) * a.input_scale:
        mu, var = pred.predict(x)
        ref_mu, ref_var = gpa.reference_predict(a, x[None])
        np.testing.assert_array_equal(mu, ref_mu[0])
        np.testing.assert_array_equal(var, ref_var[0])
        hand_mu, hand_var = gp_by_hand(a, x)
        np.testing.assert_allclose(mu, hand_mu, rtol=1e-9, atol=1e-15)
        np.testing.assert_allclose(var, hand_var, rtol=1e-9)
    np.testing.assert_allclose(pred.prior_variance, a.output_scale ** 2 * a.outputscale, rtol=0)


def test_gains_at_the_upper_bounds_far_from_the_data(params):
    law = tl.gp_law(params)
    out = law(quat_of([0.6, -0.5, 0.4]), np.array([0.15, -0.15, 0.15]), np.zeros(3))
    assert out.gains.tolist() == [9.0, 130.0]
    assert np.all(np.abs(out.mu) < 1e-12)


def test_gains_near_the_lower_bounds_on_an_inducing_point_and_rising_away(params):
    a = params.gp.arrays
    law = tl.gp_law(params)
    z = a.Z[2] * a.input_scale
    q, w = quat_of(z[:3]), z[3:6]
    on = law(q, w, np.zeros(3))
    # on Z_j: Nyström part ≈ jitter, S part ≈ 0.04 (R = 0.2 I, w ≈ unit vector): s ≈ 0.04
    assert 3.0 <= on.gains[0] < 3.0 + 0.1 * 6.0 and 50.0 <= on.gains[1] < 50.0 + 0.1 * 80.0
    gains = [law(quat_of(z[:3] + t * np.array([0.3, 0.2, -0.2])), w + t * np.array([0.03, -0.03, 0.02]),
                 np.zeros(3)).gains for t in (0.0, 0.5, 1.0, 2.0)]
    k1s = [g[0] for g in gains]
    assert k1s == sorted(k1s) and k1s[-1] > k1s[0] + 4.0
    for g in gains:
        assert 3.0 <= g[0] <= 9.0 and 50.0 <= g[1] <= 130.0
        assert (g[1] - 50.0) / 80.0 == pytest.approx((g[0] - 3.0) / 6.0, abs=1e-12)   # one schedule s


@pytest.mark.parametrize("q_v, w, h", [
    ([0.05, -0.02, 0.03], [0.004, 0.001, -0.002], [3.0, -5.0, 8.0]),
    ([-0.15, 0.1, 0.0], [-0.01, 0.02, 0.005], [20.0, 0.0, -10.0]),
    ([0.3, 0.3, -0.2], [0.05, 0.0, 0.0], [0.0, 0.0, 0.0]),
])
def test_the_gp_law_is_the_section_5_formula(params, q_v, w, h):
    a = params.gp.arrays
    q, w, h = quat_of(q_v), np.array(w), np.array(h)
    mu, var = gp_by_hand(a, np.concatenate([q_v, w, np.zeros(3)]))
    s = min(1.0, max(var / (a.output_scale ** 2 * a.outputscale)))
    K1, K2 = 3.0 + 6.0 * s, 50.0 + 80.0 * s
    u = -K1 * np.array(q_v) - K2 * w + np.cross(w, J @ w + h) - mu
    out = tl.gp_law(params)(q, w, h)
    np.testing.assert_allclose(out.torque, np.clip(u, -0.4, 0.4), rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(out.gains, [K1, K2], rtol=1e-12)
    np.testing.assert_allclose(out.mu, mu, rtol=1e-9, atol=1e-15)


def test_the_baseline_uses_the_files_lower_gains_limit_and_inertia(params):
    q_v, w, h = np.array([0.02, -0.01, 0.05]), np.array([0.003, -0.002, 0.001]), np.array([10.0, -4.0, 2.0])
    out = tl.baseline_law(params)(quat_of(q_v), w, h)
    np.testing.assert_allclose(out.torque, -3.0 * q_v - 50.0 * w + np.cross(w, J @ w + h), rtol=1e-12)
    assert out.gains.tolist() == [3.0, 50.0] and not out.mu.any()
    big = tl.baseline_law(params)(quat_of([0.5, 0.0, 0.0]), np.zeros(3), np.zeros(3))
    assert big.torque.tolist() == [-0.4, 0.0, 0.0]
