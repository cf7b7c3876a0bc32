"""Issue 25 (defects 9, 10, 12): a tuning folder's documents are checked where they are read. A NaN
or infinite objective in a shard is corrupt (never the best triple, never a bare NaN in result.json),
a plan or sidecar that is not a JSON object is a one-line error, every JSON the tool writes is
strict, and the grid is checked against the configuration's ranges before any shard runs."""
from __future__ import annotations

import hashlib
import json

import numpy as np
import pytest

from codegen import atomic
from codegen.errors import CodegenError
from host.control.nn_controller import default_package_config
from host.errors import HostError
from host.learn.samples import npz_bytes
from host.sim.targets import staring_targets
from host.tune.pid_grid import PidGrid, grid
from host.tune.pid_tuning import PLAN_FILE, TuningPlan, open_directory, read_shard, shard_paths, tune, write_shard

TWO = PidGrid("two", (10.0, 17.0), (0.0,), (46.0,))
TARGET = tuple((t.name, t.lon, t.lat, i) for i, t in enumerate(staring_targets()[:1]))


def _plan(**kw) -> TuningPlan:
    return TuningPlan(**{"grid": TWO, "targets": TARGET, "seeds": (0,), "duration": 12.0, "shard_size": 2, **kw})


def _arrays(plan: TuningPlan) -> dict:
    """Shard 0's arrays with made-up finite objectives: triple 0 is the best on every axis."""
    shape = (len(plan.targets), len(plan.grid), len(plan.seeds), 3)
    J_A = np.ones(shape)
    J_A[:, 0] = 0.5
    return {"triples": plan.grid.triples(0, len(plan.grid)), "J_A_axis": J_A, "J_w_axis": np.zeros(shape),
            "saturated_steps": np.zeros(shape[:3], np.int64)}


def _finished_shard(folder, plan: TuningPlan) -> dict:
    open_directory(folder, plan)
    arrays = _arrays(plan)
    write_shard(folder, plan, {"index": 0, "arrays": arrays, "seconds": 0.0})
    return arrays


def _reseal(folder, arrays: dict) -> None:
    """Replace shard 0's npz and record its new size and sha256 in the sidecar (what a careless edit does)."""
    npz, sidecar_path = shard_paths(folder, 0)
    data = npz_bytes(arrays)
    npz.write_bytes(data)
    sidecar = json.loads(sidecar_path.read_text())
    sidecar.update(npz_bytes=len(data), npz_sha256=hashlib.sha256(data).hexdigest())
    sidecar_path.write_text(json.dumps(sidecar))


@pytest.mark.parametrize("bad", [np.nan, np.inf])
def test_a_non_finite_objective_in_a_shard_is_refused_as_corrupt(tmp_path, bad):
    plan = _plan()
    arrays = _finished_shard(tmp_path, plan)
    arrays["J_A_axis"][0, 1, 0, 0] = bad          # triple 1, x axis: argmin would pick a NaN
    _reseal(tmp_path, arrays)
    with pytest.raises(HostError, match=r"shard-00000\.npz: corrupt: an objective is NaN or infinite"):
        read_shard(tmp_path, plan, 0)


def test_a_simulation_giving_a_nan_objective_is_not_written_as_a_shard(tmp_path):
    plan = _plan()
    open_directory(tmp_path, plan)
    arrays = _arrays(plan)
    arrays["J_w_axis"][0, 1, 0, 2] = np.nan
    with pytest.raises(HostError, match="Kp 17, Ki 0, Kd 46 gives a NaN or infinite objective"):
        write_shard(tmp_path, plan, {"index": 0, "arrays": arrays, "seconds": 0.0})
    assert not any(p.exists() for p in shard_paths(tmp_path, 0))


def test_json_the_tool_writes_is_strict(tmp_path):
    with pytest.raises(CodegenError, match="result.json: not written: a value is NaN or infinite"):
        atomic.write_json(tmp_path / "result.json", {"best": {"x": {"objective": float("nan")}}})
    assert not (tmp_path / "result.json").exists()
    with pytest.raises(CodegenError, match="NaN or infinite"):
        atomic.write_json(tmp_path / "result.json", {"J": float("inf")})


@pytest.mark.parametrize("text", ["[]", "5", "null", '"plan"'])
def test_a_plan_file_that_is_not_an_object_is_a_one_line_error(tmp_path, text):
    (tmp_path / PLAN_FILE).write_text(text)
    with pytest.raises(HostError, match=r"tuning\.json: unreadable tuning plan \(expected a JSON object, got "):
        open_directory(tmp_path, _plan())


@pytest.mark.parametrize("text", ["[]", '{"shard": NaN}'])
def test_a_shard_sidecar_that_is_not_an_object_is_a_one_line_error(tmp_path, text):
    plan = _plan()
    _finished_shard(tmp_path, plan)
    shard_paths(tmp_path, 0)[1].write_text(text)
    with pytest.raises(HostError, match=r"shard-00000\.json: .*(not a JSON object|unreadable shard sidecar)"):
        read_shard(tmp_path, plan, 0)


@pytest.mark.parametrize("spec, key", [("kp=1.7e308,ki=0,kd=40", "kp"), ("kp=17,ki=0,kd=1e39", "kd"),
                                       ("kp=17,ki=0:1e300:1e299,kd=40", "ki")])
def test_a_grid_value_the_configuration_cannot_hold_is_refused_before_any_shard(tmp_path, spec, key):
    with pytest.raises(HostError, match=f"--grid {key}: a value the controller configuration cannot hold"):
        tune(tmp_path / "t", _plan(grid=grid(spec)), default_package_config(), workers=1, progress=False,
             processes=False)
    assert not (tmp_path / "t").exists()
