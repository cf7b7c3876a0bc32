"""`staregen tune pid`: the Table 7 grid (host.tune.pid_grid) over the targets on the batched
simulator, sharded on Dask, resumable and deterministic.

Layout of a tuning directory:

    tuning.json           plan: grid, targets (name, lon, lat, noise stream), seeds, duration,
                          k1, k2, shard size, and its hash
    shard-00000.npz       triples (g,3) · J_A_axis, J_w_axis (T,g,N,3) · saturated_steps (T,g,N)
    shard-00000.json      sidecar: index, first triple, count, plan hash, npz size and sha256, timing
    result.json           best triple per axis, the objective, Table 1 beside it, the check run
    controller.toml       the controller configuration with the tuned gains (sealed)

Shard i holds triples [i·shard_size, …) of the grid over every target and seed; its content depends
only on the plan, never on the worker count or the order shards finish (the batched simulator draws
each target's noise from its seed and stream alone), so the best gains are the same whatever the
cluster. A shard is finished when its sidecar exists and validates (npz written first, both
atomically); a killed run resumes with the unfinished shards; a swapped or edited shard is refused
(its triples must be the plan's, its bytes the sidecar's).
"""
from __future__ import annotations

import hashlib
import io
import json
import time
import zipfile
from dataclasses import dataclass, field
from pathlib import Path
from typing import Sequence

import numpy as np

from codegen import atomic
from codegen.package import config as pc
from host.control.pid import TABLE1_GAINS
from host.errors import HostError
from host.outputs import check_output_folder, file_marker_owner
from host.learn.samples import npz_bytes
from host.learn.shards import check_place, read_bound_npz, read_json
from host.sim.batched import GainSets, simulate_pid_batch
from host.sim.metrics import K1, K2
from host.plant.error_model import TABLE6_ERRORS, ErrorModel
from host.sim.simulator import SimConfig
from host.tune.pid_grid import PidGrid

PLAN_FORMAT = "staregen-pid-tuning/1"
SHARD_FORMAT = "staregen-pid-tuning-shard/1"
PLAN_FILE, RESULT_FILE, CONFIG_FILE = "tuning.json", "result.json", "controller.toml"
NPZ_ARRAYS = ("triples", "J_A_axis", "J_w_axis", "saturated_steps")
AXES = ("x", "y", "z")


@dataclass(frozen=True)
class TuningPlan:
    grid: PidGrid
    targets: tuple[tuple[str, float, float, int], ...]     # name, lon [rad], lat [rad], noise stream
    seeds: tuple[int, ...] = (0,)
    duration: float = 100.0
    shard_size: int = 60
    k1: float = K1
    k2: float = K2
    errors: ErrorModel = TABLE6_ERRORS          # the scenario's reading of Table 6
    scenario: dict | None = None                # its file's description (recorded, part of the plan's hash)

    def __post_init__(self):
        if not self.targets:
            raise HostError("tuning needs at least one target")
        if not self.seeds:
            raise HostError("tuning needs at least one seed")
        if self.shard_size < 1:
            raise HostError(f"--shard-size must be >= 1, got {self.shard_size}")
        SimConfig(duration=self.duration).control_steps   # validates the duration

    @property
    def n_shards(self) -> int:
        return -(-len(self.grid) // self.shard_size)

    def shard_range(self, index: int) -> tuple[int, int]:
        start = index * self.shard_size
        return start, min(start + self.shard_size, len(self.grid))

    def as_dict(self) -> dict:
        return {"format": PLAN_FORMAT, "grid": self.grid.as_dict(),
                "targets": [{"name": n, "lon": lon, "lat": lat, "stream": s} for n, lon, lat, s in self.targets],
                "seeds": list(self.seeds), "duration": self.duration, "shard_size": self.shard_size,
                "k1": self.k1, "k2": self.k2, "sim": _sim_facts(self.sim_config()),
                "scenario": self.scenario or {"reading": self.errors.reading}}

    def plan_hash(self) -> str:
        return hashlib.sha256(json.dumps(self.as_dict(), sort_keys=True).encode()).hexdigest()

    def sim_config(self) -> SimConfig:
        return SimConfig(duration=self.duration, errors=self.errors)


def _sim_facts(cfg: SimConfig) -> dict:
    """What of the simulator's configuration the results depend on (beyond the code itself)."""
    return {"control_period": cfg.control_period, "plant_step": cfg.plant_step, "sensor_errors": cfg.sensor_errors,
            "wheel_errors": cfg.wheel_errors, "external_torques": cfg.external_torques,
            "torque_limit": cfg.spacecraft.torque_limit}


# ----------------------------------------------------------------------------- one shard

@dataclass(frozen=True)
class ShardTask:
    plan: TuningPlan
    index: int


def same_triple_on_every_axis(triples: np.ndarray) -> GainSets:
    """(g, 3) rows (kp, ki, kd) -> gain sets flying that triple on all three axes."""
    def axis3(col):
        return np.repeat(triples[:, col:col + 1], 3, axis=1)
    return GainSets(axis3(0), axis3(1), axis3(2))


def compute_shard(task: ShardTask) -> dict:
    plan = task.plan
    start, stop = plan.shard_range(task.index)
    triples = plan.grid.triples(start, stop)
    t0 = time.perf_counter()
    res = simulate_pid_batch([(lon, lat) for _, lon, lat, _ in plan.targets], same_triple_on_every_axis(triples),
                             plan.seeds, plan.sim_config(), streams=[s for *_, s in plan.targets])
    arrays = {"triples": triples, "J_A_axis": res.J_A_axis, "J_w_axis": res.J_w_axis,
              "saturated_steps": res.saturated_steps}
    return {"index": task.index, "arrays": arrays, "seconds": time.perf_counter() - t0}


def shard_paths(directory: Path, index: int) -> tuple[Path, Path]:
    return directory / f"shard-{index:05d}.npz", directory / f"shard-{index:05d}.json"


def write_shard(directory: Path, plan: TuningPlan, result: dict) -> None:
    index, arrays = result["index"], result["arrays"]
    bad = ~(np.isfinite(arrays["J_A_axis"]) & np.isfinite(arrays["J_w_axis"])).all(axis=(0, 2, 3))
    if bad.any():   # a shard read back refuses it as corrupt; say which gains diverged instead
        kp, ki, kd = arrays["triples"][int(np.argmax(bad))]
        raise HostError(f"tuning shard {index}: the triple Kp {kp:g}, Ki {ki:g}, Kd {kd:g} gives a NaN or infinite "
                        "objective; leave it out of --grid")
    data = npz_bytes(arrays)
    npz_path, json_path = shard_paths(directory, index)
    atomic.write_bytes(npz_path, data)
    start, stop = plan.shard_range(index)
    atomic.write_json(json_path, {"format": SHARD_FORMAT, "shard": index, "first_triple": start, "count": stop - start,
                                  "plan_hash": plan.plan_hash(), "npz_bytes": len(data),
                                  "npz_sha256": hashlib.sha256(data).hexdigest(),
                                  "seconds": round(result["seconds"], 3)})


def read_shard(directory: Path, plan: TuningPlan, index: int) -> dict:
    """The arrays of a finished shard, bound to its place in the plan; anything else is a HostError."""
    npz_path, json_path = shard_paths(directory, index)
    sidecar = read_json(json_path, "shard sidecar")
    start, stop = plan.shard_range(index)
    check_place(json_path, sidecar, {"format": SHARD_FORMAT, "shard": index, "first_triple": start,
                                     "count": stop - start, "plan_hash": plan.plan_hash()}, index, "plan")
    data = read_bound_npz(npz_path, json_path, sidecar)
    try:
        with np.load(io.BytesIO(data), allow_pickle=False) as npz:
            arrays = {k: npz[k] for k in NPZ_ARRAYS}
    except (OSError, ValueError, KeyError, zipfile.BadZipFile, EOFError) as exc:
        raise HostError(f"{npz_path}: not a tuning shard ({type(exc).__name__})") from None
    shape = (len(plan.targets), stop - start, len(plan.seeds))
    if (not np.array_equal(arrays["triples"], plan.grid.triples(start, stop))
            or arrays["J_A_axis"].shape != (*shape, 3) or arrays["J_w_axis"].shape != (*shape, 3)):
        raise HostError(f"{npz_path}: its triples or shapes are not shard {index}'s (a swapped shard); "
                        f"delete {npz_path.name} and {json_path.name} to recompute it")
    # argmin would pick a NaN as the best triple and write it to result.json: a corrupt shard
    if not all(np.isfinite(arrays[k]).all() for k in ("J_A_axis", "J_w_axis")):
        raise HostError(f"{npz_path}: corrupt: an objective is NaN or infinite; "
                        f"delete {npz_path.name} and {json_path.name} to recompute it")
    return arrays


def check_existing_plan(directory: Path, plan: TuningPlan) -> None:
    """A tuning folder's plan file, when there is one, is a JSON object of this plan."""
    path = directory / PLAN_FILE
    if path.exists() and read_json(path, "tuning plan").get("plan_hash") != plan.plan_hash():
        raise HostError(f"{directory} holds a tuning run of another plan (grid, targets, seeds, duration or "
                        "shard size differ); use another --out")


def open_directory(directory: Path, plan: TuningPlan) -> list[int]:
    """Create the directory and its plan, or check an existing one; returns the finished shards."""
    path = directory / PLAN_FILE
    if path.exists():
        check_existing_plan(directory, plan)
    else:   # a new tuning folder: never one holding files of something else
        check_output_folder(directory, file_marker_owner(PLAN_FILE), replaced=False)
        atomic.write_json(path, {**plan.as_dict(), "plan_hash": plan.plan_hash()})
    for tmp in directory.glob(".shard-*.tmp"):
        tmp.unlink(missing_ok=True)
    done = []
    for index in range(plan.n_shards):
        if shard_paths(directory, index)[1].exists():
            read_shard(directory, plan, index)
            done.append(index)
    return done


# ----------------------------------------------------------------------------- the best gains

@dataclass
class TuningResult:
    objective: np.ndarray                 # (G, 3) mean over targets and seeds of each axis's eq. 8 share
    best_index: tuple[int, int, int]
    best: GainSets                        # one gain set: the best triple of each axis
    table1_index: tuple[int | None, ...]  # Table 1's triple of each axis on the grid, or None
    check: dict = field(default_factory=dict)

    def best_triple(self, axis: int) -> tuple[float, float, float]:
        return float(self.best.kp[0, axis]), float(self.best.ki[0, axis]), float(self.best.kd[0, axis])


def best_gains(plan: TuningPlan, shards: Sequence[dict]) -> TuningResult:
    """Per axis, the triple minimising that axis's share of eq. 8 averaged over targets and seeds
    (the lowest grid index on a tie)."""
    J_A = np.concatenate([s["J_A_axis"] for s in shards], axis=1)
    J_w = np.concatenate([s["J_w_axis"] for s in shards], axis=1)
    objective = (plan.k1 * J_A + plan.k2 * J_w).mean(axis=(0, 2))            # (G, 3)
    best_index = tuple(int(np.argmin(objective[:, a])) for a in range(3))
    triples = plan.grid.triples()
    best = GainSets(*(np.array([[triples[best_index[a], c] for a in range(3)]]) for c in range(3)))
    t1 = TABLE1_GAINS
    table1_index = tuple(plan.grid.index_of(float(t1.kp[a]), float(t1.ki[a]), float(t1.kd[a])) for a in range(3))
    return TuningResult(objective, best_index, best, table1_index)


def check_run(plan: TuningPlan, result: TuningResult) -> dict:
    """Fly Table 1 and the tuned gains (a different triple per axis: the coupling the per-axis
    argmin ignores is in this run) over the same targets and seeds: J̄ of eq. 25-27 for both."""
    t1 = TABLE1_GAINS
    gains = GainSets(np.vstack([t1.kp, result.best.kp[0]]), np.vstack([t1.ki, result.best.ki[0]]),
                     np.vstack([t1.kd, result.best.kd[0]]))
    res = simulate_pid_batch([(lon, lat) for _, lon, lat, _ in plan.targets], gains, plan.seeds, plan.sim_config(),
                             streams=[s for *_, s in plan.targets])
    out = {}
    for g, name in enumerate(("table1", "tuned")):
        J_A, J_w = float(res.J_A[:, g].mean()), float(res.J_w[:, g].mean())
        out[name] = {"J_A": J_A, "J_w": J_w, "J": plan.k1 * J_A + plan.k2 * J_w}
    out["ratio_tuned_to_table1"] = out["tuned"]["J"] / out["table1"]["J"]
    return out


def check_grid_fits(grid: PidGrid, base: pc.PackageConfig) -> None:
    """Every gain of the grid is one the configuration can hold: each distinct value put in `base`'s
    PID gains and validated by the configuration's own rules (as tuned_config will, but before a
    shard runs, not after the whole grid)."""
    data = base.to_mapping()
    for key in ("kp", "ki", "kd"):
        values = sorted(set(getattr(grid, key)))
        for i in range(0, len(values), 3):       # three values per trial: a gain is a vec3
            chunk = values[i:i + 3]
            try:
                pc.from_mapping({**data, "pid": {**data["pid"], key: chunk + chunk[-1:] * (3 - len(chunk))}},
                                sealed=False)
            except pc.ConfigError as exc:
                raise HostError(f"--grid {key}: a value the controller configuration cannot hold ({exc})") from None


def tuned_config(result: TuningResult, base: pc.PackageConfig) -> pc.PackageConfig:
    """The configuration with the tuned gains in place of its PID gains (everything else kept)."""
    data = base.to_mapping()
    data["pid"].update(kp=[float(v) for v in result.best.kp[0]], ki=[float(v) for v in result.best.ki[0]],
                       kd=[float(v) for v in result.best.kd[0]])
    return pc.from_mapping(data, sealed=False)


def result_document(plan: TuningPlan, result: TuningResult, timing: dict) -> dict:
    axes = {}
    for a, name in enumerate(AXES):
        kp, ki, kd = result.best_triple(a)
        i1 = result.table1_index[a]
        axes[name] = {"kp": kp, "ki": ki, "kd": kd, "grid_index": result.best_index[a],
                      "objective": float(result.objective[result.best_index[a], a]),
                      "table1_on_grid": i1 is not None,
                      "table1_objective": None if i1 is None else float(result.objective[i1, a])}
    return {"format": "staregen-pid-tuning-result/1", "plan_hash": plan.plan_hash(), "grid": plan.grid.name,
            "triples": len(plan.grid), "targets": len(plan.targets), "seeds": list(plan.seeds),
            "duration": plan.duration, "scenario": plan.scenario or {"reading": plan.errors.reading},
            "best": axes, "check": result.check, "timing": timing}


def tune(directory, plan: TuningPlan, base_config: pc.PackageConfig, scheduler: str | None = None,
         workers: int | None = None, progress: bool = True, processes: bool = True) -> dict:
    """Compute the unfinished shards on Dask, pick the best gains, fly the check run, write
    result.json and controller.toml. Returns the result document."""
    from host.learn.distributed import dask_client, run_tasks

    directory = Path(directory)
    check_grid_fits(plan.grid, base_config)
    check_existing_plan(directory, plan)      # before any worker starts
    start = time.perf_counter()
    done = set(open_directory(directory, plan))   # a folder that is not a tuning folder: refused before any cluster
    with dask_client(scheduler, workers, processes=processes) as client:
        todo = [i for i in range(plan.n_shards) if i not in done]
        per_scenario = len(plan.targets) * len(plan.seeds)
        weights = [(plan.shard_range(i)[1] - plan.shard_range(i)[0]) * per_scenario for i in todo]
        n_workers = len(client.scheduler_info(n_workers=-1)["workers"])
        compute_start = time.perf_counter()
        for res in run_tasks(client, compute_shard, [ShardTask(plan, i) for i in todo], weights, "tune pid",
                             progress, unit="scenario"):
            write_shard(directory, plan, res)
        compute = time.perf_counter() - compute_start
    shards = [read_shard(directory, plan, i) for i in range(plan.n_shards)]
    result = best_gains(plan, shards)
    check_start = time.perf_counter()
    result.check = check_run(plan, result)
    scenarios = sum(weights)
    timing = {"workers": n_workers, "shards_kept": len(done), "shards_computed": len(todo),
              "scenarios_computed": scenarios, "compute_seconds": round(compute, 3),
              "scenarios_per_second": round(scenarios / compute, 2) if compute > 0 and scenarios else None,
              "check_seconds": round(time.perf_counter() - check_start, 3),
              "wall_seconds": round(time.perf_counter() - start, 3)}
    doc = result_document(plan, result, timing)
    pc.write(tuned_config(result, base_config), directory / CONFIG_FILE,
             {"pid": f"staregen tune pid --grid {plan.grid.name} (plan {plan.plan_hash()[:12]})"})
    atomic.write_json(directory / RESULT_FILE, doc)
    return doc
