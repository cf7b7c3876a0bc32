"""`staregen gp table1`: the Table 1 harness from the command line (tiny synthetic sizes here; the paper-
scale run is a benchmark, BENCHMARKS.md). `staregen gp train`: the trained model, its law file and
Figs. 2-3, on a tiny pool (the command's seed lists and run length monkeypatched)."""
from __future__ import annotations

import hashlib
import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import host.cli.gp as gp_cli
from codegen.units.gp import artifact as gpa
from codegen.units.gp.params import load_params
from host.learn import gp_train
from host.plant.spacecraft import TABLE6_INERTIA
from host.sim.takeover import collect
from host.cli import main
from tests.host.cli.package_inputs import cli


def test_table1_writes_rows_with_growth_ratios_beside_the_papers(tmp_path, capsys):
    out = tmp_path / "t1"
    code, stdout, err = cli(capsys, "gp", "table1", "--data", "synthetic", "--sizes", "40,80", "--m", "5",
                            "--exact-iterations", "3", "--sparse-iterations", "5", "--out", str(out))
    assert code == 0, err
    doc = json.loads((out / "table1.json").read_text())
    assert [r["n"] for r in doc["rows"]] == [40, 80] and doc["m"] == 5
    first, second = doc["rows"]
    assert first["exact_growth"] == 1.0 and second["exact_growth"] == second["exact_time_s"] / first["exact_time_s"]
    assert all(r["exact_mse"] > 0 and r["sparse_mse"] > 0 for r in doc["rows"])
    assert doc["paper"]["exact_s"] == [6.31, 303.78] and doc["paper"]["sparse_s"] == [1.56, 3.64]
    assert "paper: exact 6.31 -> 303.78 s (48x)" in stdout


# ----------------------------------------------------------------------------- gp train


TINY_POOL, TINY_TEST, TINY_SECONDS = (0, 1), (100,), 40.0


@pytest.fixture
def tiny(monkeypatch):
    """Two 40 s pool runs and one 40 s test run instead of 10 + 4 runs of 300 s."""
    _tiny(monkeypatch)


def _tiny(mp) -> None:
    mp.setattr(gp_cli, "TRAIN_SEEDS", TINY_POOL)
    mp.setattr(gp_cli, "TEST_SEEDS", TINY_TEST)
    mp.setattr(gp_cli, "RUN_SECONDS", TINY_SECONDS)


@pytest.fixture(scope="module")
def trained(tmp_path_factory):
    """One tiny training for the module: (folder, stdout)."""
    out = tmp_path_factory.mktemp("train") / "gp"
    with pytest.MonkeyPatch.context() as mp:
        _tiny(mp)
        code = main(["gp", "train", "--m", "6", "--iterations", "30", "--seed", "3", "--out", str(out)])
    assert code == 0
    return out, (out / "train.json").read_text()


def test_train_writes_a_loadable_law_file_naming_the_sealed_artifact(trained):
    out, stdout = trained
    assert {p.name for p in out.iterdir()} == {"gp.json", "gp_law.toml", "train.json", "fig2_gp_response.png",
                                              "fig3_gp_error.png"}
    params = load_params(out / "gp_law.toml")
    assert params.artifact_name == "gp.json" and params.n_inducing == 6
    assert (params.k1, params.k1_bar, params.k2, params.k2_bar, params.torque_max) == (4.0, 16.0, 72.0, 144.0, 1.0)
    np.testing.assert_allclose(np.array(params.inertia), TABLE6_INERTIA, rtol=1e-7)   # float32-checked values
    assert gpa.load(out / "gp.json").sha256 == params.gp.sha256
    assert '"n_train": 78' in stdout


def test_train_metadata_records_the_pool_hash_and_the_held_out_mse(trained):
    out, _ = trained
    art = gpa.load(out / "gp.json")
    meta = art.metadata
    pool, test = collect(TINY_POOL, TINY_SECONDS), collect(TINY_TEST, TINY_SECONDS)
    h = hashlib.sha256(pool["x"].astype("<f8").tobytes() + pool["d"].astype("<f8").tobytes()).hexdigest()
    assert meta["dataset_sha256"] == h
    assert (meta["n_train"], meta["m"], meta["iterations"], meta["seed"]) == (len(pool["x"]), 6, 30, 3)
    mean, _ = gpa.reference_predict(art.arrays, test["x"])          # the sealed model, float64, no gpytorch
    np.testing.assert_allclose(meta["test_mse"], np.mean((mean - test["d"]) ** 2, axis=0), rtol=1e-6)
    assert meta["train_time_s"] > 0


def test_train_json_r2_and_std_agree_with_the_mse(trained):
    out, _ = trained
    doc = json.loads((out / "train.json").read_text())
    test = collect(TINY_TEST, TINY_SECONDS)
    var_d = np.var(test["d"], axis=0)
    np.testing.assert_allclose(doc["test"]["r2_per_axis"], 1.0 - np.array(doc["test"]["mse_per_axis"]) / var_d,
                               rtol=1e-9)
    np.testing.assert_allclose(np.array(doc["test"]["rms_error_per_axis"]) ** 2, doc["test"]["mse_per_axis"], rtol=1e-9)
    assert all(0.0 <= c <= 1.0 for c in doc["test"]["band95_coverage_per_axis"])
    assert all(s > 0 for s in doc["train"]["mean_predicted_std_per_axis"])
    assert doc["n_test"] == len(test["x"]) and doc["law_sha256"] == load_params(out / "gp_law.toml").sha256()


def test_train_refuses_to_finish_when_the_law_file_does_not_load(tiny, tmp_path, capsys, monkeypatch):
    monkeypatch.setattr(gp_train, "law_toml", lambda *a, **k: 'artifact = "gp.json"\nk1 = -4.0\n')
    out = tmp_path / "gp"
    code, stdout, err = cli(capsys, "gp", "train", "--m", "4", "--iterations", "2", "--out", str(out))
    assert code == 2 and err.count("\n") == 1 and "the law file does not load" in err, err
    assert not out.exists()
    assert "pool: run 2/2 (seed 1, 40 s)" in stdout and "training the sparse GP: M = 4" in stdout   # progress


@pytest.mark.parametrize("argv, message", [
    (["--m", "1"], "--m must be at least 2"),
    (["--m", "201"], "--m must be at most 200"),
    (["--m", "x"], "--m must be an integer"),
    (["--iterations", "0"], "--iterations must be at least 1"),
    (["--seed", "-1"], "--seed"),
])
def test_train_bad_options_are_one_line(tmp_path, capsys, argv, message):
    code, _, err = cli(capsys, "gp", "train", *argv, "--out", str(tmp_path / "o"))
    assert code == 2 and err.count("\n") == 1 and message in err, err
    assert not (tmp_path / "o").exists()


def test_train_refuses_m_above_the_pool_and_a_foreign_folder(tmp_path, capsys, monkeypatch):
    monkeypatch.setattr(gp_cli, "TRAIN_SEEDS", (0,))
    monkeypatch.setattr(gp_cli, "TEST_SEEDS", (100,))
    monkeypatch.setattr(gp_cli, "RUN_SECONDS", 10.0)        # 9 samples
    code, _, err = cli(capsys, "gp", "train", "--m", "20", "--out", str(tmp_path / "o"))
    assert code == 2 and "more than the training pool (9 samples)" in err and err.count("\n") == 1, err
    foreign = tmp_path / "foreign"
    foreign.mkdir()
    (foreign / "notes.txt").write_text("mine")
    code, _, err = cli(capsys, "gp", "train", "--out", str(foreign))
    assert code == 2 and "not this command's own output" in err, err
    assert (foreign / "notes.txt").read_text() == "mine"


def test_the_command_runs_as_a_module_too():
    """`python3 -m host.cli` is the installed `staregen` (a checkout on PYTHONPATH, no pip install)."""
    res = subprocess.run([sys.executable, "-m", "host.cli", "verify", "--unit", "gp", "--period", "0.1", "--params",
                          "docs/gp_paper004.toml"], capture_output=True, text=True, cwd=Path(__file__).resolve().parents[3])
    assert res.returncode == 2 and res.stderr.strip() == "staregen verify: error: --period does not apply to unit gp"
