"""Training, baselines and sweep (issue 6 items 3-4), on small synthetic data made here.

The data: S_in drawn in the Table 2 box, torques from a known smooth map (a fixed tanh layer plus
a linear part, about the size of the real commands), so every test runs in seconds.
"""
from __future__ import annotations

import json
import socket
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from codegen import artifact as art
from codegen.units.network import reference
from codegen.units.network import golden
from host.learn import sweep, training
from host.control.baselines import LinearLS, SaturatedLinear, pd_ff_features
from host.cli import main as cli_main
from host.errors import HostError
from host.learn.ocp import OcpConfig
from host.learn.samples import DatasetPlan, draw_inputs, open_dataset_dir, write_shard

LOW, HIGH = np.array(art.TABLE2_MIN, dtype=np.float64), np.array(art.TABLE2_MAX, dtype=np.float64)
SMALL_HIDDEN = 6
QUICK = replace(training.DEFAULT_RECIPE, epochs=150, adam_steps=100)

# Golden (float32 C mirror) vs the float64 torch net: float32 rounding of weights, inputs and
# every operation, plus sg_tanhf. Stated tolerance: 2e-6 of the largest |torque| plus 1e-6 relative.
GOLDEN_ABS_TOL_FRACTION = 2e-6
GOLDEN_REL_TOL = 1e-6


def smooth_map(X: np.ndarray) -> np.ndarray:
    """A known smooth S_in -> torque map (N·m, |M| ≲ 0.4)."""
    rng = np.random.default_rng(1234)
    xn = 2 * (X - LOW) / (HIGH - LOW) - 1
    A, B = rng.normal(size=(12, 3)) / 4, rng.normal(size=(12, 3)) / 20
    return 0.2 * np.tanh(xn @ A) + xn @ B


def synthetic(n: int, seed: int = 0) -> tuple[np.ndarray, np.ndarray]:
    X = LOW + (HIGH - LOW) * np.random.default_rng(seed).random((n, 12))
    return X, smooth_map(X)


def fake_dataset(directory: Path, n: int, shard_size: int = 100) -> Path:
    """A dataset folder in the format of `staregen samples`, commands from smooth_map (no IPOPT)."""
    plan = DatasetPlan(n_samples=n, ocp=OcpConfig(), master_seed=0, shard_size=shard_size).validate()
    open_dataset_dir(directory, plan)
    for i in range(plan.n_shards):
        count = plan.shard_count(i)
        s_in = draw_inputs(plan.master_seed, i, count)
        arrays = {"s_in": s_in, "command": smooth_map(s_in), "status": np.array(["Solve_Succeeded"] * count, "<U48"),
                  "iterations": np.full(count, 5, dtype=np.int32), "objective": np.ones(count)}
        timing = {"solve_seconds": [0.01] * count, "solve_cpu_seconds": [0.01] * count, "wall_seconds": 0.1,
                  "cpu_seconds": 0.1, "worker": "test"}
        write_shard(directory, plan, {"index": i, "arrays": arrays, "timing": timing})
    return directory


def one_line_cli_error(capsys, argv: list[str]) -> str:
    rc = cli_main(argv)
    err = capsys.readouterr().err.strip()
    assert rc == 2 and err and "\n" not in err, (rc, err)
    return err


# ----------------------------------------------------------------------------- split and mapminmax

def test_split_is_deterministic_for_a_seed_and_75_25():
    a_train, a_test = training.split_indices(1000, seed=3)
    b_train, b_test = training.split_indices(1000, seed=3)
    assert np.array_equal(a_train, b_train) and np.array_equal(a_test, b_test)
    assert len(a_train) == 750 and len(a_test) == 250
    assert np.array_equal(np.sort(np.concatenate([a_train, a_test])), np.arange(1000))
    c_train, _ = training.split_indices(1000, seed=4)
    assert not np.array_equal(a_train, c_train)


def test_mapminmax_is_matlabs_definition_from_the_training_set_only():
    X, Y = synthetic(400)
    X[:, 5] = 0.003  # a constant row: MATLAB passes it through unchanged
    split = training.make_split(X, Y, seed=0)
    x = split.X_train
    assert np.array_equal(split.input_map.xmin, x.min(axis=0)) and np.array_equal(split.input_map.xmax, x.max(axis=0))
    # MATLAB: y = (ymax - ymin) * (x - xmin) / (xmax - xmin) + ymin, [ymin, ymax] = [-1, 1]
    xmin, xmax = x.min(axis=0), x.max(axis=0)
    varying = xmax > xmin
    expected = 2 * (x[:, varying] - xmin[varying]) / (xmax[varying] - xmin[varying]) - 1
    xn = split.xn_train
    assert np.allclose(xn[:, varying], expected, rtol=0, atol=1e-6)  # float32-rounded gain and offset
    assert np.allclose(xn[:, varying].min(axis=0), -1, atol=1e-6)
    assert np.allclose(xn[:, varying].max(axis=0), 1, atol=1e-6)
    assert np.allclose(xn[:, 5], x[:, 5], rtol=0, atol=1e-15)  # (x + 1) - 1
    yn = split.yn_train
    assert np.allclose(yn.min(axis=0), -1, atol=1e-6) and np.allclose(yn.max(axis=0), 1, atol=1e-6)
    back = training.mapminmax_reverse(split.output_map, yn)
    assert np.allclose(back, split.Y_train, rtol=0, atol=1e-15)


# ----------------------------------------------------------------------------- the trained artifact

def test_trained_artifact_reproduces_torch_float64_through_golden(tmp_path):
    X, Y = synthetic(500)
    split = training.make_split(X, Y, seed=0)
    fit = training.fit_network(split, "tansig", SMALL_HIDDEN, QUICK, seed=0)
    artifact = training.export(fit, split, art.default_metadata(creator="test"))
    loaded = art.load(artifact.save(tmp_path / "m.json"))
    torch64 = training.predict_physical(fit, split, split.X_test)
    flight = golden.network_eval(loaded, split.X_test.astype(np.float32)).astype(np.float64)
    tol = GOLDEN_ABS_TOL_FRACTION * np.abs(torch64).max() + GOLDEN_REL_TOL * np.abs(torch64)
    assert np.all(np.abs(flight - torch64) <= tol), np.abs(flight - torch64).max()
    # the net learned the map (so the comparison is not between two trivial outputs)
    assert training.error_metrics(split.Y_test, torch64, split.output_map)["relative_torque_error"] < 0.05
    # and the tolerance is tight enough to see a 1e-4 change of one weight
    W1 = loaded.W1.copy()
    W1[0, 0] += 1e-4
    nudged = art.from_arrays(W1, loaded.b1, loaded.W2, loaded.b2, split.input_map.xmin, split.input_map.xmax,
                             split.output_map.xmin, split.output_map.xmax)
    moved = golden.network_eval(nudged, split.X_test.astype(np.float32)).astype(np.float64)
    assert np.any(np.abs(moved - torch64) > tol)


def test_train_artifact_metadata_metrics_and_same_bytes_for_the_same_seed():
    X, Y = synthetic(400)
    a1, r1 = training.train_artifact((X, Y, {}), recipe=QUICK, seed=5, hidden=SMALL_HIDDEN)
    a2, _ = training.train_artifact((X, Y, {}), recipe=QUICK, seed=5, hidden=SMALL_HIDDEN)
    a3, _ = training.train_artifact((X, Y, {}), recipe=QUICK, seed=6, hidden=SMALL_HIDDEN)
    assert a1.to_json() == a2.to_json()
    assert a1.to_json() != a3.to_json()
    meta = a1.metadata
    assert meta["dataset_sha256"] == training.dataset_sha256(X, Y) and meta["seed"] == 5
    assert meta["test_mse"] == r1.net["mse_mean_normalised"] and meta["recipe"]["epochs"] == 150
    assert meta["network"] == {"sizes": [12, SMALL_HIDDEN, 3], "activations": ["tansig", "purelin"]}
    # eq. 24 is the sum over the 3 x N_test normalised errors; the mean divides it by 3 N_test
    assert r1.n_test == 100 and np.isclose(r1.net["mse_eq24_sum_normalised"], 300 * r1.net["mse_mean_normalised"])
    # the reported errors are those of the exported float32 weights
    split = training.make_split(X, Y, seed=5)
    direct = training.error_metrics(split.Y_test, reference.reference_eval64(a1, split.X_test), split.output_map)
    assert direct == r1.net


def test_paper_recipe_uses_dropout_weight_decay_and_sgd():
    X, Y = synthetic(300)
    recipe = training.recipe_named("paper", epochs=3)
    assert (recipe.optimiser, recipe.dropout, recipe.weight_decay) == ("sgdm", 0.1, 0.01)
    split = training.make_split(X, Y, seed=0)
    fit = training.fit_network(split, "tansig", SMALL_HIDDEN, recipe, seed=0)
    assert any(type(m).__name__ == "Dropout" for m in fit.net)
    assert [type(m).__name__ for m in training.exportable_net(fit)] == ["Linear", "Tanh", "Linear"]


# ----------------------------------------------------------------------------- baselines

def test_linear_least_squares_recovers_a_linear_law_exactly():
    X, _ = synthetic(200)
    rng = np.random.default_rng(7)
    W, b = rng.normal(size=(12, 3)), rng.normal(size=3)
    Y = X @ W + b
    model = LinearLS.fit(X, Y)
    assert np.allclose(model.coef[:12], W, rtol=1e-8, atol=1e-8) and np.allclose(model.coef[12], b, rtol=1e-10)
    Xn, _ = synthetic(50, seed=1)
    assert np.allclose(model.predict(Xn), Xn @ W + b, rtol=0, atol=1e-10)


def test_saturated_linear_recovers_pd_feedforward_law_and_its_clipping():
    X, _ = synthetic(600)
    rng = np.random.default_rng(8)
    K = rng.normal(size=(9, 3)) * np.r_[[10.0] * 3, [50.0] * 3, [1.0] * 3][:, None]
    b = np.array([0.01, -0.02, 0.0])
    bound = 0.15
    Y = np.clip(pd_ff_features(X) @ K + b, -bound, bound)
    model = SaturatedLinear.fit(X, Y, bound)
    assert all(0 < n < len(X) for n in model.n_fit)  # saturated samples were left out of each axis's fit
    assert np.allclose(model.coef[:9], K, rtol=1e-7, atol=1e-9) and np.allclose(model.coef[9], b, atol=1e-12)
    assert np.allclose(model.predict(X), Y, rtol=0, atol=1e-12)
    # a plain linear fit of the same data cannot do this
    assert np.abs(LinearLS.fit(X, Y).predict(X) - Y).max() > 1e-3


# ----------------------------------------------------------------------------- sweep

def _result(act, hidden, epochs, mse):
    return {"activation": act, "hidden": hidden, "epochs": epochs, "mse_mean_normalised": mse,
            "mse_eq24_sum_normalised": mse * 300, "relative_torque_error": mse, "train_mse_normalised": mse,
            "train_seconds": 1.0}


def test_sweep_selects_minimum_test_mse_and_exports_the_best_tansig():
    results = [_result("tansig", 20, 200, 3e-4), _result("relu", 40, 700, 1e-4), _result("tansig", 40, 700, 2e-4),
               _result("logsig", 60, 200, 5e-4),
               {"activation": "relu", "hidden": 60, "epochs": 700, "error": "diverged"}]
    best, best_tansig = sweep.select(results)
    assert (best["activation"], best["hidden"]) == ("relu", 40)
    assert (best_tansig["activation"], best_tansig["hidden"], best_tansig["epochs"]) == ("tansig", 40, 700)
    choice = sweep.choice_of(results, full=False, recipe="default")
    assert choice["best_tansig"]["activation"] == "tansig" and "relu won" in choice["exported"]
    assert choice["n_diverged"] == 1 and "train_seconds" not in choice["best_overall"]
    with pytest.raises(HostError, match="no tansig"):
        sweep.choice_of([r for r in results if r["activation"] != "tansig"], full=False, recipe="default")


def test_grids_are_table3_and_the_reduced_default():
    full = sweep.grid(full=True)
    assert len(full) == 3876 == 4 * 51 * 19
    assert {p.activation for p in full} == {"tansig", "logsig", "sigmoid", "relu"}
    assert min(p.hidden for p in full) == 10 and max(p.hidden for p in full) == 60
    assert sorted({p.epochs for p in full}) == list(range(100, 1001, 50))
    assert len(sweep.grid()) == 18


def test_activation_names_map_to_matlabs_functions():
    import torch

    n = torch.linspace(-3, 3, 13, dtype=torch.float64)
    expected = {"tansig": 2 / (1 + torch.exp(-2 * n)) - 1, "logsig": 1 / (1 + torch.exp(-n)),
                "sigmoid": n / (1 + n.abs()), "relu": torch.clamp(n, min=0)}
    for name, want in expected.items():
        assert torch.allclose(training.activation_module(name)(n), want, rtol=0, atol=1e-15), name
    with pytest.raises(HostError, match="unknown activation"):
        training.activation_module("softmax")


def test_sweep_on_dask_end_to_end(tmp_path):
    X, Y = synthetic(300)
    points = [sweep.SweepPoint(a, h, 60) for a in ("tansig", "relu", "logsig") for h in (3, 5)]
    result = sweep.run_sweep((X, Y, {}), points=points, workers=1, progress=False)
    scored = [r for r in result.results if "error" not in r]
    assert len(result.results) == len(points)
    best = min(scored, key=lambda r: r["mse_mean_normalised"])
    assert result.choice["best_overall"]["mse_mean_normalised"] == best["mse_mean_normalised"]
    tansig = min((r for r in scored if r["activation"] == "tansig"), key=lambda r: r["mse_mean_normalised"])
    assert (result.report.hidden, result.report.recipe["epochs"]) == (tansig["hidden"], tansig["epochs"])
    # the client's retrained net is the one the worker scored (training is deterministic)
    assert result.report.train_mse_normalised == tansig["train_mse_normalised"]
    paths = sweep.write_sweep(result, tmp_path)
    loaded = art.load(paths["artifact"])
    assert loaded.n_hidden == tansig["hidden"] and loaded.metadata["choice"] == result.choice
    assert json.loads(paths["json"].read_text())["choice"]["best_tansig"]["activation"] == "tansig"


# ----------------------------------------------------------------------------- CLI and bad input

def test_cli_train_writes_a_loadable_artifact(tmp_path, capsys):
    data = fake_dataset(tmp_path / "data", 300)
    out = tmp_path / "model.json"
    assert cli_main(["train", "--data", str(data), "--out", str(out), "--hidden", "4", "--epochs", "50"]) == 0
    loaded = art.load(out)
    assert loaded.sizes == (12, 4, 3) and loaded.metadata["dataset"]["n_used"] == 300
    assert "linear least squares" in capsys.readouterr().out


@pytest.mark.parametrize("make", ["missing", "empty", "corrupt"])
def test_cli_train_bad_data_folder_is_one_line_and_writes_nothing(tmp_path, capsys, make):
    data = tmp_path / "data"
    if make != "missing":
        data.mkdir()
    if make == "corrupt":
        fake_dataset(data, 200)
        shard = data / "shard-00001.npz"
        shard.write_bytes(shard.read_bytes()[:100])
    out = tmp_path / "model.json"
    one_line_cli_error(capsys, ["train", "--data", str(data), "--out", str(out)])
    assert list(tmp_path.glob("model.json*")) == [] and list(tmp_path.glob(".model.json*")) == []


def test_too_few_usable_samples_is_one_line(tmp_path, capsys):
    data = fake_dataset(tmp_path / "data", 200)
    out = tmp_path / "model.json"
    err = one_line_cli_error(capsys, ["train", "--data", str(data), "--out", str(out)])
    assert "200 usable samples, fewer than the 858 needed" in err and not out.exists()
    assert training.minimum_samples(40) == 858
    X, Y = synthetic(50)
    with pytest.raises(HostError, match="fewer than"):
        training.train_artifact((X, Y, {}), hidden=SMALL_HIDDEN)


def test_non_finite_or_misshaped_data_is_refused():
    X, Y = synthetic(300)
    Y[3, 1] = np.nan
    with pytest.raises(HostError, match="non-finite"):
        training.train_artifact((X, Y, {}), hidden=SMALL_HIDDEN)
    with pytest.raises(HostError, match="must be X"):
        training.train_artifact((X[:, :11], Y, {}), hidden=SMALL_HIDDEN)


@pytest.mark.parametrize("where", ["parent-is-a-file", "is-a-folder", "no-parent"])
def test_unwritable_out_fails_before_training_with_one_line(tmp_path, capsys, where):
    data = fake_dataset(tmp_path / "data", 300)
    blocker = tmp_path / "file.txt"
    blocker.write_text("x")
    out = {"parent-is-a-file": blocker / "model.json", "is-a-folder": data,
           "no-parent": tmp_path / "nowhere" / "model.json"}[where]
    err = one_line_cli_error(capsys, ["train", "--data", str(data), "--out", str(out), "--hidden", "4"])
    assert str(out) in err
    assert not (tmp_path / "nowhere").exists() and blocker.read_text() == "x"


def test_sweep_cli_bad_input_is_one_line(tmp_path, capsys):
    blocker = tmp_path / "file.txt"
    blocker.write_text("x")
    data = fake_dataset(tmp_path / "data", 300)
    assert "cannot create the sweep folder" in one_line_cli_error(
        capsys, ["sweep", "--data", str(data), "--out", str(blocker / "sweep")])
    one_line_cli_error(capsys, ["sweep", "--data", str(tmp_path / "absent"), "--out", str(tmp_path / "s")])
    assert "fewer than the 1284 needed to train a 12-60-3 net" in one_line_cli_error(
        capsys, ["sweep", "--data", str(data), "--out", str(tmp_path / "s1")])
    one_line_cli_error(capsys, ["train", "--data", str(data), "--out", str(tmp_path / "m.json"), "--epochs", "0"])
    with socket.socket() as s:  # a port nobody listens on
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    big = fake_dataset(tmp_path / "big", 1300, shard_size=650)  # enough for the grid's 12-60-3 nets
    err = one_line_cli_error(capsys, ["sweep", "--data", str(big), "--out", str(tmp_path / "s2"),
                                      "--scheduler", f"tcp://127.0.0.1:{port}", "--connect-timeout", "1"])
    assert "cannot reach the Dask scheduler" in err and not (tmp_path / "s2" / "model.json").exists()
