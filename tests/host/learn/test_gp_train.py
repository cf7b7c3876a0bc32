"""host.learn.gp_train without training: the pool hash, the law's file, the regression statistics
(docs/gp-takeover.md §3, §5; `staregen gp train` is tested end to end in tests/host/cli/test_cli_gp.py)."""
from __future__ import annotations

import numpy as np
import pytest

from codegen.units.gp.example import example_artifact
from codegen.units.gp.params import GpParamsError, load_params
from host.learn import gp_train


def test_dataset_hash_sees_every_value_and_the_split_between_x_and_d():
    rng = np.random.default_rng(0)
    x, d = rng.normal(size=(5, 9)), rng.normal(size=(5, 3))
    h = gp_train.dataset_sha256(x, d)
    x2 = x.copy()
    x2[4, 8] = np.nextafter(x2[4, 8], np.inf)
    assert gp_train.dataset_sha256(x2, d) != h
    assert gp_train.dataset_sha256(x, d) == h
    assert gp_train.dataset_sha256(x.astype(np.float32).astype(np.float64), d) != h


def test_the_law_file_loads_with_the_section_5_constants(tmp_path):
    example_artifact(m=5).save(tmp_path / "model.json")
    (tmp_path / "law.toml").write_text(gp_train.law_toml("model.json"))
    p = load_params(tmp_path / "law.toml")
    assert (p.k1, p.k1_bar, p.k2, p.k2_bar, p.torque_max) == (4.0, 16.0, 72.0, 144.0, 1.0)
    assert p.artifact_name == "model.json" and p.n_inducing == 5
    assert p.inertia[1][1] == pytest.approx(304.86, rel=1e-7) and p.inertia[0][2] == pytest.approx(-25.1, rel=1e-7)


def test_the_law_file_names_a_missing_artifact_in_one_line(tmp_path):
    (tmp_path / "law.toml").write_text(gp_train.law_toml("absent.json"))
    with pytest.raises(GpParamsError) as exc:
        load_params(tmp_path / "law.toml")
    assert "absent.json" in str(exc.value) and "\n" not in str(exc.value)


class _StubFit:
    """predict(x, noise) -> a mean off by +0.1 on x, 0 on y, −0.3 on z and a standard deviation 0.1."""

    def predict(self, x, noise=False):
        assert noise
        mean = np.tile([0.1, 0.0, -0.3], (len(x), 1)) + x[:, :3]
        return mean, np.full((len(x), 3), 0.01)


def test_regression_stats_against_hand_values():
    x = np.zeros((4, 9))
    x[:, 0] = [0.0, 1.0, 2.0, 3.0]
    d = x[:, :3].copy()                      # var d_x = 1.25, d_y = d_z = 0
    d[:, 1] = [1.0, -1.0, 1.0, -1.0]         # var d_y = 1
    s = gp_train.regression_stats(_StubFit(), x, d)
    # errors: x 0.1 each, y −d_y (±1), z −0.3
    np.testing.assert_allclose(s["mse_per_axis"], [0.01, 1.0, 0.09])
    np.testing.assert_allclose(s["r2_per_axis"][:2], [1.0 - 0.01 / 1.25, 0.0])
    np.testing.assert_allclose(s["mean_predicted_std_per_axis"], [0.1, 0.1, 0.1])
    assert s["band95_coverage_per_axis"] == [1.0, 0.0, 0.0]       # |0.1| <= 0.196; 1 and 0.3 are outside
