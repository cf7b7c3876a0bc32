"""Issue 27: ground learning of paper 004's GP on data arrays (docs/gp-takeover.md §2-4, §6, §8).

Synthetic data (gp.synthetic: a smooth known map + noise), small N and few iterations so the
module runs in seconds; one torch thread.
"""
from __future__ import annotations

import numpy as np
import pytest

torch = pytest.importorskip("torch")
gpytorch = pytest.importorskip("gpytorch")
torch.set_num_threads(1)

from codegen.units.gp import artifact as gpa  # noqa: E402
from host.learn import gp, gp_table1  # noqa: E402

N, M = 150, 8


@pytest.fixture(scope="module")
def data():
    return gp.synthetic(N, seed=0), gp.synthetic(200, seed=1)


@pytest.fixture(scope="module")
def sparse(data):
    (x, d), _ = data
    return gp.train_sparse(x, d, m=M, iterations=150)


@pytest.fixture(scope="module")
def exact(data):
    (x, d), _ = data
    return gp.train_exact(x, d, iterations=40)


def test_normalisation_uses_the_fixed_scales_and_rms_outputs():
    assert gp.INPUT_SCALES.tolist() == [0.2] * 3 + [0.01] * 3 + [5e-4] * 3
    x = np.tile(gp.INPUT_SCALES, (2, 1))
    assert np.array_equal(gp.normalise_x(x), np.ones((2, 9)))
    d = np.array([[3.0, 0.0, 1.0], [-4.0, 0.0, -1.0]])
    assert np.allclose(gp.output_scales(d), [np.sqrt(12.5), 1.0, 1.0])


def test_cholesky_is_forced_above_gpytorchs_default():
    import linear_operator
    assert gpytorch.settings.max_cholesky_size is linear_operator.settings.max_cholesky_size
    assert linear_operator.settings.max_cholesky_size.value() < 2000 <= gp.MAX_CHOLESKY_SIZE


def test_bad_data_refused():
    with pytest.raises(ValueError):
        gp.train_sparse(np.zeros((10, 6)), np.zeros((10, 3)))
    with pytest.raises(ValueError):
        gp.check_data(np.full((4, 9), np.nan), np.zeros((4, 3)))


def test_exact_gp_learns_the_map(data, exact):
    _, (xt, dt) = data
    assert exact.losses[-1] < exact.losses[0]
    mean, var = exact.predict(xt)
    assert mean.shape == var.shape == (len(xt), 3) and (var > 0).all()
    assert gp.mse(mean, dt)["mse"] < 0.3 * float(np.mean(dt ** 2))
    assert exact.train_time_s > 0


def test_sparse_gp_learns_the_map_with_shared_z_and_kernel(data, sparse):
    _, (xt, dt) = data
    assert sparse.losses[-1] < sparse.losses[0]
    mean, var = sparse.predict(xt)
    assert mean.shape == var.shape == (len(xt), 3) and (var > 0).all()
    assert gp.mse(mean, dt)["mse"] < 0.3 * float(np.mean(dt ** 2))
    base = sparse.model.variational_strategy.base_variational_strategy
    assert tuple(base.inducing_points.shape) == (M, 9)                      # shared Z
    assert sparse.model.covar_module.base_kernel.lengthscale.shape == (1, 9)  # one kernel
    assert tuple(base._variational_distribution.variational_mean.shape) == (3, M)
    _, var_noisy = sparse.predict(xt, noise=True)
    assert (var_noisy > var).all()


def test_reference_predictor_reproduces_gpytorch(data, sparse):
    """§6 from the arrays only (float64, no gpytorch) = model(x) at data points and far outside."""
    (x, _), (xt, _) = data
    a = gp.flight_arrays(sparse)
    for X in (x, xt, 30.0 * xt):
        m_gpt, v_gpt = sparse.predict(X)
        m_ref, v_ref = gpa.reference_predict(a, X)
        assert np.max(np.abs(m_ref - m_gpt)) <= 1e-6 * np.max(np.abs(m_gpt)) + 1e-300
        assert np.allclose(v_ref, v_gpt, rtol=1e-6, atol=0)
    far_m, far_v = gpa.reference_predict(a, 30.0 * xt)      # far: prior variance, mean -> 0
    assert np.allclose(far_v, (a.outputscale + a.jitter) * a.output_scale ** 2, rtol=1e-9)
    assert np.max(np.abs(far_m)) < 1e-6 * np.max(a.output_scale)


def test_folded_flight_arrays_match_the_reference_at_zero_omega_dot(data, sparse):
    """The float32 flight arrays (ω̇ folded into c) evaluated in float64 agree with the float64 reference."""
    _, (xt, _) = data
    x0 = xt.copy()
    x0[:, 6:] = 0.0
    a = gp.flight_arrays(sparse)
    m_ref, v_ref = gpa.reference_predict(a, x0)
    m_fl, v_fl = gpa.flight_predict(a.flight(), x0[:, :3], x0[:, 3:6])
    assert np.max(np.abs(m_fl - m_ref)) <= 1e-4 * np.max(np.abs(m_ref))
    # flight kxx omits GPyTorch's jitter; float32 A' limits the Nyström cancellation near the data
    assert np.max(np.abs(v_fl - v_ref)) <= 1e-3 * a.outputscale * np.max(a.output_scale ** 2)


def test_artifact_from_a_trained_model_round_trips(tmp_path, data, sparse):
    (x, _), _ = data
    g = gp.artifact_from(sparse, metadata={"test_mse": None})
    path = g.save(tmp_path / "gp.json")
    loaded = gpa.load(path)
    assert loaded.to_json() == path.read_text()
    assert loaded.metadata["gpytorch"] == gpytorch.__version__
    assert np.array_equal(loaded.envelope_min, x.min(0))
    m1, v1 = gpa.reference_predict(loaded.arrays, x)
    m2, v2 = gpa.reference_predict(gp.flight_arrays(sparse), x)
    assert np.array_equal(m1, m2) and np.array_equal(v1, v2)


def test_table1_small(data):
    (x, d), (xt, dt) = data
    rows = gp_table1.table1(x, d, xt, dt, sizes=(60, 120), m=6, exact_iterations=10, sparse_iterations=20)
    assert [r["n"] for r in rows] == [60, 120]
    assert rows[0]["exact_growth"] == rows[0]["sparse_growth"] == 1.0
    for r in rows:
        assert r["exact_time_s"] > 0 and r["sparse_time_s"] > 0
        assert np.isfinite(r["exact_mse"]) and np.isfinite(r["sparse_mse"]) and r["mse_ratio"] > 0
    with pytest.raises(ValueError):
        gp_table1.table1(x, d, xt, dt, sizes=(N + 1,))
