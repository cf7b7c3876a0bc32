"""Distributed sample creation: determinism, resume after a kill, shard validation, one-line errors."""
from __future__ import annotations

import json
import os
import signal
import socket
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from host.cli import main as cli_main
from host.errors import HostError
from host.learn.ocp import OcpConfig
from host.learn.samples import (TABLE2_HIGH, TABLE2_LOW, DatasetPlan, ShardTask, compute_shard, create_dataset,
                          draw_inputs, finished_shards, load_dataset, npz_bytes, open_dataset_dir, shard_paths,
                          write_shard)

REPO = Path(__file__).resolve().parents[3]


def _fake_result(plan: DatasetPlan, index: int, statuses=None) -> dict:
    """A shard result without IPOPT: real inputs, made-up commands (for the I/O tests)."""
    count = plan.shard_count(index)
    rng = np.random.default_rng(100 + index)
    statuses = statuses or ["Solve_Succeeded"] * count
    arrays = {"s_in": draw_inputs(plan.master_seed, index, count), "command": rng.normal(size=(count, 3)),
              "status": np.array(statuses, dtype="<U48"), "iterations": np.full(count, 5, dtype=np.int32),
              "objective": rng.random(count)}
    timing = {"solve_seconds": [0.01] * count, "solve_cpu_seconds": [0.01] * count, "wall_seconds": 0.1,
              "cpu_seconds": 0.1, "worker": "test"}
    return {"index": index, "arrays": arrays, "timing": timing}


def _fake_dataset(directory: Path, plan: DatasetPlan) -> None:
    open_dataset_dir(directory, plan)
    for i in range(plan.n_shards):
        write_shard(directory, plan, _fake_result(plan, i))


def _one_line_error(excinfo) -> str:
    message = str(excinfo.value)
    assert message and "\n" not in message
    return message


# ----------------------------------------------------------------------------- inputs and files


def test_table2_box_equals_the_artifact_envelope():
    from codegen.artifact import TABLE2_MAX, TABLE2_MIN
    assert np.array_equal(TABLE2_LOW, TABLE2_MIN) and np.array_equal(TABLE2_HIGH, TABLE2_MAX)


def test_shard_inputs_depend_on_master_seed_and_shard_index_only():
    a = draw_inputs(7, 3, 50)
    assert np.array_equal(a, draw_inputs(7, 3, 50))
    assert np.array_equal(a[:20], draw_inputs(7, 3, 20))           # a short last shard is a prefix
    assert not np.array_equal(a, draw_inputs(7, 4, 50))
    assert not np.array_equal(a, draw_inputs(8, 3, 50))
    assert np.all(a >= TABLE2_LOW) and np.all(a <= TABLE2_HIGH)
    spread = (a.max(0) - a.min(0)) / (TABLE2_HIGH - TABLE2_LOW)
    assert np.all(spread > 0.8)


def test_npz_bytes_are_deterministic_and_loadable(tmp_path):
    arrays = _fake_result(DatasetPlan(4, OcpConfig(), shard_size=4), 0)["arrays"]
    first = npz_bytes(arrays)
    time.sleep(1.1)                                    # zip timestamps have a 2 s resolution
    assert npz_bytes(arrays) == first
    (tmp_path / "x.npz").write_bytes(first)
    with np.load(tmp_path / "x.npz", allow_pickle=False) as npz:
        assert np.array_equal(npz["status"], arrays["status"])
        assert np.array_equal(npz["command"], arrays["command"])


def test_load_dataset_excludes_failed_solves_by_the_stated_rule(tmp_path):
    plan = DatasetPlan(5, OcpConfig(), shard_size=2)
    open_dataset_dir(tmp_path, plan)
    write_shard(tmp_path, plan, _fake_result(plan, 0, ["Solve_Succeeded", "Maximum_Iterations_Exceeded"]))
    nan_result = _fake_result(plan, 1)
    nan_result["arrays"]["command"][1] = np.nan
    write_shard(tmp_path, plan, nan_result)
    write_shard(tmp_path, plan, _fake_result(plan, 2, ["Solved_To_Acceptable_Level"]))
    X, Y, status, report = load_dataset(tmp_path)
    assert X.shape == (2, 12) and Y.shape == (2, 3) and list(status) == ["Solve_Succeeded"] * 2
    assert np.all(np.isfinite(Y))
    assert report["n_total"] == 5 and report["n_used"] == 2 and report["n_excluded"] == 3
    assert report["excluded_by_status"] == {"Maximum_Iterations_Exceeded": 1, "Solve_Succeeded": 1,
                                            "Solved_To_Acceptable_Level": 1}
    X_all, _, status_all, _ = load_dataset(tmp_path, include_failed=True)
    assert X_all.shape == (5, 12) and len(status_all) == 5


# ----------------------------------------------------------------------------- damaged datasets


def test_corrupt_truncated_foreign_or_missing_shards_are_one_line_errors(tmp_path):
    plan = DatasetPlan(6, OcpConfig(), shard_size=2)
    _fake_dataset(tmp_path, plan)
    load_dataset(tmp_path)
    npz0, json0 = shard_paths(tmp_path, 0)
    good = npz0.read_bytes()

    damaged = bytearray(good)
    damaged[len(damaged) // 2] ^= 0xFF
    npz0.write_bytes(bytes(damaged))
    with pytest.raises(HostError) as excinfo:
        load_dataset(tmp_path)
    assert "corrupt" in _one_line_error(excinfo)
    with pytest.raises(HostError):                     # the resume path refuses it too
        finished_shards(tmp_path, plan)

    npz0.write_bytes(good[: len(good) // 3])
    with pytest.raises(HostError) as excinfo:
        load_dataset(tmp_path)
    assert "truncated" in _one_line_error(excinfo)
    npz0.write_bytes(good)

    sidecar = json.loads(json0.read_text())
    json0.write_text(json.dumps({**sidecar, "config_hash": "0" * 64}))
    with pytest.raises(HostError) as excinfo:
        load_dataset(tmp_path)
    assert "config hash" in _one_line_error(excinfo)
    json0.write_text(json.dumps(sidecar))

    shard_paths(tmp_path, 2)[1].unlink()
    with pytest.raises(HostError) as excinfo:
        load_dataset(tmp_path)
    assert "incomplete" in _one_line_error(excinfo)


@pytest.mark.parametrize("target, text, needle", [
    ("manifest", "[]", "dataset.json: unreadable dataset manifest (expected a JSON object, got list)"),
    ("sidecar", "[]", "shard-00000.json: unreadable shard sidecar (expected a JSON object, got list)"),
    ("sidecar", '{"shard": 0, "shard": 1}', "shard-00000.json: unreadable shard sidecar (not valid JSON: duplicate key"),
    ("manifest", None, "dataset.json: malformed dataset manifest (KeyError"),
])
def test_a_manifest_or_sidecar_that_is_not_the_expected_object_is_one_line(tmp_path, target, text, needle):
    """Issue 25: `[]` in dataset.json or a shard sidecar was an AttributeError traceback."""
    _fake_dataset(tmp_path, DatasetPlan(4, OcpConfig(), shard_size=2))
    manifest = tmp_path / "dataset.json"
    if text is None:    # the right format, its other fields gone
        text = json.dumps({"format": json.loads(manifest.read_text())["format"]})
    (manifest if target == "manifest" else shard_paths(tmp_path, 0)[1]).write_text(text)
    with pytest.raises(HostError) as excinfo:
        load_dataset(tmp_path)
    assert needle in _one_line_error(excinfo)


def test_swapped_or_edited_shards_are_refused(tmp_path):
    """Issue 14 defect 5: shard 1 copied over shard 0 (npz + sidecar), or a sidecar's index, first
    sample, seed or statistics edited, is refused: each shard is bound to its place and content."""
    plan = DatasetPlan(6, OcpConfig(), shard_size=2)
    _fake_dataset(tmp_path, plan)
    load_dataset(tmp_path)
    (npz0, json0), (npz1, json1) = shard_paths(tmp_path, 0), shard_paths(tmp_path, 1)
    saved = npz0.read_bytes(), json0.read_text()
    npz0.write_bytes(npz1.read_bytes())
    json0.write_text(json1.read_text())
    with pytest.raises(HostError) as excinfo:
        load_dataset(tmp_path)
    assert "shard" in _one_line_error(excinfo)
    npz0.write_bytes(saved[0])
    sidecar = json.loads(saved[1])
    edits = [("shard", 1), ("first_sample", 2), ("n_samples", 3), ("seed", {"master_seed": 1, "spawn_key": [0]}),
             ("statistics", {**sidecar["statistics"], "iterations_max": 999})]
    for key, value in edits:
        json0.write_text(json.dumps({**sidecar, key: value}))
        with pytest.raises(HostError) as excinfo:
            load_dataset(tmp_path)
        assert key in _one_line_error(excinfo), key
    json0.write_text(saved[1])
    load_dataset(tmp_path)


def test_a_directory_of_another_configuration_is_refused(tmp_path):
    open_dataset_dir(tmp_path, DatasetPlan(6, OcpConfig(), shard_size=2))
    with pytest.raises(HostError) as excinfo:
        open_dataset_dir(tmp_path, DatasetPlan(6, OcpConfig(objective="paper-l1"), shard_size=2))
    assert "another configuration" in _one_line_error(excinfo)
    with pytest.raises(HostError) as excinfo:
        open_dataset_dir(tmp_path, DatasetPlan(8, OcpConfig(), shard_size=2))
    assert "N=6" in _one_line_error(excinfo)


# ----------------------------------------------------------------------------- the CLI's one-line errors


@pytest.mark.parametrize("n", ["0", "-3", "ten"])
def test_cli_rejects_a_non_positive_sample_count(tmp_path, capsys, n):
    out = tmp_path / "ds"
    assert cli_main(["samples", f"--n={n}", "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip()
    assert "--n" in err and len(err.splitlines()) == 1
    assert not out.exists()


def test_cli_reports_an_unreachable_scheduler_in_one_line(tmp_path, capsys):
    with socket.socket() as s:                         # a port nobody listens on
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    out = tmp_path / "ds"
    start = time.monotonic()
    code = cli_main(["samples", "--n", "4", "--scheduler", f"tcp://127.0.0.1:{port}", "--connect-timeout", "2",
                     "--out", str(out)])
    assert code == 2 and time.monotonic() - start < 20
    err = capsys.readouterr().err.strip()
    assert "cannot reach the Dask scheduler" in err and len(err.splitlines()) == 1
    assert not out.exists()


def test_cli_creates_a_dataset_and_a_rerun_keeps_it(tmp_path, capsys):
    out = tmp_path / "ds"
    argv = ["samples", "--n", "3", "--shard-size", "2", "--workers", "1", "--objective", "paper-l1",
            "--no-progress", "--out", str(out)]
    assert cli_main(argv) == 0
    first = capsys.readouterr().out
    assert "3 samples in 2 shards (0 finished shards kept, 2 computed)" in first
    X, Y, status, report = load_dataset(out)
    assert X.shape == (3, 12) and report["objective"] == "paper-l1" and report["n_used"] == 3
    assert cli_main(argv) == 0
    assert "(2 finished shards kept, 0 computed)" in capsys.readouterr().out


def test_cli_weights_reach_the_ocp_and_move_the_optimum(tmp_path, capsys):
    """--k1/--k2/--effort-weight are recorded in dataset.json and change the solved commands."""
    base = ["samples", "--n", "2", "--shard-size", "2", "--workers", "1", "--no-progress", "--out"]
    assert cli_main(base + [str(tmp_path / "d")]) == 0
    assert cli_main(base + [str(tmp_path / "w"), "--k1", "0.5", "--k2", "30", "--effort-weight", "0.01"]) == 0
    capsys.readouterr()
    ocp = json.loads((tmp_path / "w" / "dataset.json").read_text())["ocp"]
    assert (ocp["k1"], ocp["k2"], ocp["effort_weight"]) == (0.5, 30.0, 0.01)
    (Xd, Yd, _, _), (Xw, Yw, _, _) = load_dataset(tmp_path / "d"), load_dataset(tmp_path / "w")
    assert np.array_equal(Xd, Xw) and not np.allclose(Yd, Yw, rtol=1e-3, atol=0)


# ----------------------------------------------------------------------------- determinism and resume (real solves)


def _npz_and_stable_sidecars(directory: Path) -> dict:
    files = {}
    for path in sorted(directory.glob("shard-*")):
        if path.suffix == ".json":
            sidecar = json.loads(path.read_text())
            sidecar.pop("timing")
            files[path.name] = sidecar
        else:
            files[path.name] = path.read_bytes()
    return files


def test_one_and_two_workers_give_byte_identical_shards(tmp_path):
    plan = DatasetPlan(8, OcpConfig(), master_seed=11, shard_size=2)
    one = create_dataset(tmp_path / "one", plan, workers=1, progress=False)
    two = create_dataset(tmp_path / "two", plan, workers=2, progress=False)
    assert one["workers"] == 1 and two["workers"] == 2 and one["shards_computed"] == 4
    a, b = _npz_and_stable_sidecars(tmp_path / "one"), _npz_and_stable_sidecars(tmp_path / "two")
    assert len(a) == 8 and a == b
    assert (tmp_path / "one" / "dataset.json").read_bytes() == (tmp_path / "two" / "dataset.json").read_bytes()
    X, Y, status, report = load_dataset(tmp_path / "one")
    assert X.shape == (8, 12) and report["n_used"] == 8 and np.all(np.abs(Y) < 1.0)


def test_an_existing_scheduler_runs_the_same_shards(tmp_path):
    import logging

    from distributed import LocalCluster

    plan = DatasetPlan(4, OcpConfig(), master_seed=11, shard_size=2)
    with LocalCluster(n_workers=1, threads_per_worker=1, processes=False, dashboard_address=":0",
                      silence_logs=logging.ERROR) as cluster:
        run = create_dataset(tmp_path, plan, scheduler=cluster.scheduler_address, progress=False)
    assert run["workers"] == 1 and run["shards_computed"] == 2
    for i in range(plan.n_shards):
        reference = compute_shard(ShardTask(i, plan.shard_count(i), plan.master_seed, plan.ocp))
        assert shard_paths(tmp_path, i)[0].read_bytes() == npz_bytes(reference["arrays"])


def test_a_killed_run_resumes_without_recomputing_finished_shards(tmp_path):
    out = tmp_path / "ds"
    n, shard_size, seed = 30, 2, 5
    argv = ["samples", "--n", str(n), "--shard-size", str(shard_size), "--seed", str(seed), "--workers", "1",
            "--no-progress", "--out", str(out)]
    code = "import sys; from host.cli import main; sys.exit(main(sys.argv[1:]))"
    proc = subprocess.Popen([sys.executable, "-c", code, *argv], cwd=REPO, start_new_session=True,
                            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    try:
        deadline = time.monotonic() + 60
        while not (out / "shard-00000.json").exists() and not (out / "shard-00001.json").exists():
            assert proc.poll() is None and time.monotonic() < deadline, "the run ended before its first shard"
            time.sleep(0.01)
    finally:
        os.killpg(proc.pid, signal.SIGKILL)             # the CLI and its Dask worker processes
        proc.wait()
    plan = DatasetPlan(n, OcpConfig(), master_seed=seed, shard_size=shard_size)
    done = finished_shards(out, plan)
    assert 1 <= len(done) < plan.n_shards
    before = {i: os.stat(shard_paths(out, i)[0]) for i in done}

    run = create_dataset(out, plan, workers=1, processes=False, progress=False)
    assert run["shards_kept"] == len(done) and run["shards_computed"] == plan.n_shards - len(done)
    for i, st in before.items():
        now = os.stat(shard_paths(out, i)[0])
        assert (now.st_ino, now.st_mtime_ns) == (st.st_ino, st.st_mtime_ns)

    for i in range(plan.n_shards):                      # the same dataset as an uninterrupted run
        reference = compute_shard(ShardTask(i, plan.shard_count(i), seed, plan.ocp))
        assert shard_paths(out, i)[0].read_bytes() == npz_bytes(reference["arrays"])
    X, _, _, report = load_dataset(out)
    assert report["n_total"] == n and not list(out.glob(".*.tmp"))
