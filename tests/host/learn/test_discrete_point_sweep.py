"""The discrete-point accuracy sweep: measures against hand-computed errors, every grid row present,
the network row refused when the artifact was trained on other samples."""
from __future__ import annotations

import numpy as np
import pytest

from codegen.units.dp.params import DpParams
from host.control.nn_controller import load_artifact
from host.errors import HostError
from host.learn.discrete_point_sweep import markdown, measure, sweep


def test_measure_is_papers_mean_abs_error_and_our_relative_error():
    Y = np.array([[1.0, -2.0, 0.0], [0.0, 2.0, 1.0]])
    P = Y + np.array([[0.1, 0.0, 0.0], [0.0, -0.3, 0.0]])
    a = measure("x", Y, P)
    assert a.mean_abs_error == pytest.approx(0.4 / 6) and a.max_abs_error == pytest.approx(0.3)
    assert a.relative_torque_error == pytest.approx(np.sqrt(0.1) / np.sqrt(10.0))


def test_sweep_on_affine_samples_has_every_row_and_tiny_errors():
    rng = np.random.default_rng(0)
    X = rng.uniform(-1, 1, (400, 12))
    Y = X @ rng.normal(size=(12, 3)) + 0.5
    rows = sweep(X, Y, (0.05, 0.2), (32, 64), DpParams(n_min=26))
    assert [r.label for r in rows][:2] == ["PD + feed-forward (saturated linear)", "linear least squares"]
    dp = rows[2:]
    assert len(dp) == 4 and all(r.relative_torque_error < 1e-4 for r in dp)
    assert rows[1].relative_torque_error < 1e-12
    assert all(0.0 <= r.widened <= 1.0 and r.found_median >= 26 for r in dp)
    assert markdown(rows).count("\n| discrete point") == 4


def test_network_trained_elsewhere_is_refused():
    rng = np.random.default_rng(1)
    X = rng.uniform(-1, 1, (100, 12))
    with pytest.raises(HostError, match="not trained on this dataset"):
        sweep(X, X[:, :3], (0.1,), (32,), DpParams(), network=load_artifact(None))
