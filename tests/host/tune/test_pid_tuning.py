"""`staregen tune pid`: the grid, the per-axis argmin, sharding on Dask (deterministic whatever the
worker count, resumable, swapped or edited shards refused), the check run and the tuned
configuration the flight package reads."""
from __future__ import annotations

import json
import shutil

import numpy as np
import pytest

from codegen.package import config as pc
from host.cli import main
from host.control.nn_controller import default_package_config
from host.control.pid import TABLE1_GAINS
from host.errors import HostError
from host.sim.batched import simulate_pid_batch
from host.sim.targets import staring_targets
from host.tune.pid_grid import GRIDS, PidGrid
from host.tune.pid_tuning import (TuningPlan, best_gains, open_directory, read_shard, same_triple_on_every_axis,
                                  shard_paths, tune)

SMALL = PidGrid("small", (10.0, 17.0, 40.0), (0.0, 0.03), (46.0, 80.0))   # 12 triples
TARGETS = tuple((t.name, t.lon, t.lat, i) for i, t in enumerate(staring_targets()[:2]))


def _plan(**kw) -> TuningPlan:
    args = {"grid": SMALL, "targets": TARGETS, "seeds": (0,), "duration": 12.0, "shard_size": 5}
    args.update(kw)
    return TuningPlan(**args)


def test_table7_grid_is_the_papers_and_holds_table1():
    g = GRIDS["table7"]
    assert len(g) == 60 * 4 * 51
    assert g.kp[0] == 1.0 and g.kp[-1] == 60.0 and g.ki == (0.0, 0.01, 0.02, 0.03) and g.kd[0] == 40.0 and g.kd[-1] == 90.0
    for grid_ in GRIDS.values():
        for a in range(3):
            i = grid_.index_of(float(TABLE1_GAINS.kp[a]), float(TABLE1_GAINS.ki[a]), float(TABLE1_GAINS.kd[a]))
            assert i is not None
            assert tuple(grid_.triples(i, i + 1)[0]) == (TABLE1_GAINS.kp[a], TABLE1_GAINS.ki[a], TABLE1_GAINS.kd[a])
    t = SMALL.triples()
    assert t.shape == (12, 3) and tuple(t[0]) == (10.0, 0.0, 46.0) and tuple(t[1]) == (10.0, 0.0, 80.0)
    assert tuple(t[2]) == (10.0, 0.03, 46.0) and tuple(t[-1]) == (40.0, 0.03, 80.0)
    assert SMALL.index_of(99.0, 0.0, 46.0) is None


def test_argmin_is_per_axis_with_the_lowest_index_on_ties():
    plan = _plan()
    J_A = np.ones((2, 12, 1, 3))
    J_w = np.zeros((2, 12, 1, 3))
    J_A[:, 7, :, 0] = 0.5      # x: triple 7
    J_A[:, 3, :, 1] = 0.25     # y: triples 3 and 9 tie
    J_A[:, 9, :, 1] = 0.25
    J_A[0, 4, :, 2] = 0.1      # z: triple 4 best on average though worse on target 1
    J_A[1, 4, :, 2] = 1.5
    shards = [{"J_A_axis": J_A[:, :5], "J_w_axis": J_w[:, :5]}, {"J_A_axis": J_A[:, 5:], "J_w_axis": J_w[:, 5:]}]
    r = best_gains(plan, shards)
    assert r.best_index == (7, 3, 4)
    assert r.best_triple(0) == tuple(SMALL.triples(7, 8)[0])
    assert r.table1_index[0] == SMALL.index_of(17.0, 0.0, 46.0) and r.table1_index[1] is None


@pytest.fixture(scope="module")
def tuned(tmp_path_factory):
    out = tmp_path_factory.mktemp("tune") / "one"
    doc = tune(out, _plan(), default_package_config(), workers=1, progress=False, processes=False)
    return out, doc


def test_best_gains_are_the_argmin_of_a_direct_run(tuned):
    out, doc = tuned
    res = simulate_pid_batch([(lon, lat) for _, lon, lat, _ in TARGETS], same_triple_on_every_axis(SMALL.triples()),
                             (0,), _plan().sim_config(), streams=[0, 1])
    objective = res.J_axis().mean(axis=(0, 2))
    for a, name in enumerate("xyz"):
        i = int(np.argmin(objective[:, a]))
        assert doc["best"][name]["grid_index"] == i
        assert doc["best"][name]["objective"] == pytest.approx(objective[i, a], rel=1e-12)
        assert (doc["best"][name]["kp"], doc["best"][name]["ki"], doc["best"][name]["kd"]) == tuple(SMALL.triples(i, i + 1)[0])


def test_tuned_configuration_flies_the_tuned_gains(tuned):
    out, doc = tuned
    cfg = pc.load(out / "controller.toml")
    assert list(cfg.controller.kp) == [doc["best"][a]["kp"] for a in "xyz"]
    assert list(cfg.controller.kd) == [doc["best"][a]["kd"] for a in "xyz"]
    base = default_package_config()
    assert cfg.controller.torque_limit == base.controller.torque_limit and cfg.name == base.name
    c = doc["check"]
    assert c["ratio_tuned_to_table1"] == pytest.approx(c["tuned"]["J"] / c["table1"]["J"])
    assert json.loads((out / "result.json").read_text()) == doc


def test_two_workers_and_a_resume_give_the_same_result(tuned, tmp_path):
    out, doc = tuned
    two = tune(tmp_path / "two", _plan(), default_package_config(), workers=2, progress=False, processes=False)
    assert two["best"] == doc["best"] and two["check"] == doc["check"]
    for i in range(_plan().n_shards):
        assert shard_paths(tmp_path / "two", i)[0].read_bytes() == shard_paths(out, i)[0].read_bytes()
    for p in shard_paths(tmp_path / "two", 1):
        p.unlink()
    again = tune(tmp_path / "two", _plan(), default_package_config(), workers=1, progress=False, processes=False)
    assert again["timing"]["shards_kept"] == 2 and again["timing"]["shards_computed"] == 1
    assert again["best"] == doc["best"]


def test_swapped_edited_and_foreign_shards_are_refused(tuned, tmp_path):
    out, _ = tuned
    work = tmp_path / "w"
    shutil.copytree(out, work)
    plan = _plan()
    npz0, json0 = shard_paths(work, 0)
    npz1, json1 = shard_paths(work, 1)
    shutil.copy(npz0, npz1)
    shutil.copy(json0, json1)
    with pytest.raises(HostError, match="shard 1 of this plan"):
        read_shard(work, plan, 1)
    sidecar = json.loads(json0.read_text())
    sidecar["shard"], sidecar["first_triple"] = 1, 5
    json1.write_text(json.dumps(sidecar))
    with pytest.raises(HostError, match="swapped shard"):
        read_shard(work, plan, 1)
    data = bytearray(npz0.read_bytes())
    data[-10] ^= 1
    npz0.write_bytes(bytes(data))
    with pytest.raises(HostError, match="corrupt"):
        read_shard(work, plan, 0)
    with pytest.raises(HostError, match="another plan"):
        open_directory(out, _plan(seeds=(1,)))


@pytest.mark.parametrize("argv, message", [
    (["--targets", "0"], "--targets"),
    (["--targets", "101"], "at most 100"),
    (["--targets", "north"], "--targets"),
    (["--seeds", ","], "at least one seed"),
    (["--seeds", "1,1"], "twice"),
    (["--seeds", "-3"], "--seeds"),
    (["--duration", "5"], "--duration"),
    (["--shard-size", "0"], "--shard-size"),
    (["--workers", "0"], "--workers"),
    (["--grid", "fine"], "unknown grid 'fine'"),
    (["--grid", "kp=5:1:1,ki=0,kd=40"], "empty range"),
    (["--grid", "kp=1:5:0,ki=0,kd=40"], "step must be > 0"),
    (["--grid", "kp=1,ki=0"], "missing kd"),
    (["--grid", "kp=1,ki=0,kd=4,kx=1"], "unknown key 'kx'"),
    (["--grid", "kp=1:1000000:0.001,ki=0,kd=40"], "more than"),
])
def test_bad_arguments_are_one_line_errors(argv, message, tmp_path, capsys):
    assert main(["tune", "pid", "--out", str(tmp_path / "o"), *argv]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and message in err and "Traceback" not in err
    assert not (tmp_path / "o").exists()


def test_cli_tunes_and_resumes(tmp_path, capsys, monkeypatch):
    monkeypatch.setitem(GRIDS, "coarse", SMALL)
    argv = ["tune", "pid", "--grid", "coarse", "--targets", "2", "--duration", "12", "--shard-size", "6",
            "--workers", "1", "--no-progress", "--out", str(tmp_path / "t")]
    assert main(argv) == 0
    first = capsys.readouterr().out
    assert "computed 2 shard(s), kept 0" in first and "tuned configuration" in first
    assert main(argv) == 0
    assert "computed 0 shard(s), kept 2" in capsys.readouterr().out


@pytest.mark.parametrize("rows, message", [
    ("120,30\nfoo\n", ":2: expected LON,LAT"),
    ("120,95\n", ":1: target latitude 95 deg"),
    ("a,b,c\n", ":1: unknown target"),
    ("# nothing\n\n", "no targets"),
    ("120,nan\n", ":1: target"),
    (",120,30\n", ":1: a target name"),
    ("300,30\n", "below the horizon"),
])
def test_target_list_files_with_bad_rows_are_one_line_errors(rows, message, tmp_path, capsys):
    path = tmp_path / "targets.csv"
    path.write_text(rows)
    assert main(["tune", "pid", "--targets", str(path), "--out", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and message in err, err
    assert not (tmp_path / "o").exists()


def test_a_target_list_file_gives_names_and_streams(tmp_path):
    from host.cli.tune import parse_targets
    path = tmp_path / "t.csv"
    path.write_text("# staring targets\nwest, 119.5, 30.1\n120.2,29.8  # unnamed\n")
    t = parse_targets(str(path))
    assert [(n, s) for n, _, _, s in t] == [("west", 0), ("120.2,29.8", 1)]
    assert t[0][1] == pytest.approx(np.radians(119.5)) and t[1][2] == pytest.approx(np.radians(29.8))


def test_custom_grid_spec():
    from host.tune.pid_grid import grid
    g = grid("kp=1:3:1,ki=0,kd=40:50:5")
    assert (g.kp, g.ki, g.kd) == ((1.0, 2.0, 3.0), (0.0,), (40.0, 45.0, 50.0)) and len(g) == 9
    assert grid("kp=0:0.03:0.01,ki=0,kd=1").kp == (0.0, 0.01, 0.02, 0.03)
