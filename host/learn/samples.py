"""The optimal-control dataset: S_in drawn in the Table 2 box, solved by host.learn.ocp, stored in shards.

Layout of a dataset directory (docs/ocp.md, "Dataset"):

    dataset.json          manifest: N, shard size, master seed, OCP config and its hash
    shard-00000.npz       s_in (m,12) · command (m,3) N·m · status (m,) · iterations (m,) · objective (m,)
    shard-00000.json      sidecar: seeds, config hash, sha256 of the npz, solver statistics, timing

Shard i holds samples [i·shard_size, ...), drawn from SeedSequence(master_seed, spawn_key=(i,)),
so its content depends on neither the worker count nor the order shards finish in. The npz is
written with fixed zip timestamps, so equal content gives equal bytes; timing lives in the
sidecar only. The npz is written before its sidecar (both atomically): a shard is finished
when its sidecar exists and validates.
"""
from __future__ import annotations

import hashlib
import io
import json
import os
import socket
import time
import zipfile
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from host.errors import HostError
from host.learn.ocp import OcpConfig, solver_for
from host.learn.shards import check_place, read_bound_npz, read_json
from codegen import atomic

# Table 2 of paper 001, in its units (°/s, °/s², °, °/s); tests check it equals codegen's copy.
S_IN_NAMES = ("w_dx", "w_dy", "w_dz", "wdot_dx", "wdot_dy", "wdot_dz",
              "phi_bd", "theta_bd", "psi_bd", "w_ex", "w_ey", "w_ez")
TABLE2_LOW = np.array([-0.1, -1.2, -0.05, -0.005, -0.015, -0.005, -0.02, -0.02, -0.02, -0.004, -0.004, -0.004])
TABLE2_HIGH = np.array([0.1, 0.0, 0.05, 0.005, 0.015, 0.005, 0.02, 0.02, 0.02, 0.004, 0.004, 0.004])

DATASET_FORMAT = "staregen-ocp-dataset/1"
SHARD_FORMAT = "staregen-ocp-shard/1"
MANIFEST = "dataset.json"
DEFAULT_SHARD_SIZE = 250
TRAINING_STATUS = "Solve_Succeeded"
TRAINING_RULE = (f"a sample is used for training iff IPOPT returned {TRAINING_STATUS} and the command is "
                 "finite; every other sample stays in its shard with its status and is counted in the report")
NPZ_ARRAYS = {"s_in": (12,), "command": (3,), "status": (), "iterations": (), "objective": ()}
_FIXED_ZIP_TIME = (1980, 1, 1, 0, 0, 0)


# ----------------------------------------------------------------------------- plan


@dataclass(frozen=True)
class DatasetPlan:
    """What a dataset is: N samples of one OCP config, cut into shards, from one master seed."""

    n_samples: int
    ocp: OcpConfig
    master_seed: int = 0
    shard_size: int = DEFAULT_SHARD_SIZE

    def validate(self) -> "DatasetPlan":
        if self.n_samples <= 0:
            raise HostError(f"the number of samples must be > 0, got {self.n_samples}")
        if self.shard_size <= 0:
            raise HostError(f"the shard size must be > 0, got {self.shard_size}")
        if self.master_seed < 0:
            raise HostError(f"the seed must be >= 0, got {self.master_seed}")
        self.ocp.validate()
        return self

    @property
    def n_shards(self) -> int:
        return -(-self.n_samples // self.shard_size)

    def shard_count(self, index: int) -> int:
        """Samples in shard `index` (the last one may be short)."""
        return min(self.shard_size, self.n_samples - index * self.shard_size)

    def config_hash(self) -> str:
        """Everything that fixes a shard's content except N (which only shortens the last shard)."""
        payload = {"format": SHARD_FORMAT, "ocp": self.ocp.config_hash(), "seed": self.master_seed,
                   "shard_size": self.shard_size, "low": TABLE2_LOW.tolist(), "high": TABLE2_HIGH.tolist()}
        return hashlib.sha256(json.dumps(payload, sort_keys=True).encode()).hexdigest()

    def manifest(self) -> dict:
        return {
            "format": DATASET_FORMAT,
            "n_samples": self.n_samples,
            "shard_size": self.shard_size,
            "n_shards": self.n_shards,
            "master_seed": self.master_seed,
            "objective": self.ocp.objective,
            "config_hash": self.config_hash(),
            "ocp": self.ocp.to_dict(),
            "s_in": {"names": list(S_IN_NAMES), "low": TABLE2_LOW.tolist(), "high": TABLE2_HIGH.tolist()},
            "training_rule": TRAINING_RULE,
        }


def shard_seed(master_seed: int, index: int) -> np.random.SeedSequence:
    return np.random.SeedSequence(entropy=master_seed, spawn_key=(index,))


def draw_inputs(master_seed: int, index: int, count: int) -> np.ndarray:
    """S_in of shard `index`: uniform in the Table 2 box, (count, 12)."""
    rng = np.random.default_rng(shard_seed(master_seed, index))
    return TABLE2_LOW + (TABLE2_HIGH - TABLE2_LOW) * rng.random((count, 12))


# ----------------------------------------------------------------------------- compute (runs on a worker)


@dataclass(frozen=True)
class ShardTask:
    index: int
    count: int
    master_seed: int
    ocp: OcpConfig


def compute_shard(task: ShardTask) -> dict:
    """Solve every sample of one shard; returns the npz arrays and the (non-deterministic) timing."""
    start_wall, start_cpu = time.perf_counter(), time.process_time()
    solver = solver_for(task.ocp)
    s_in = draw_inputs(task.master_seed, task.index, task.count)
    command = np.full((task.count, 3), np.nan)
    status = np.empty(task.count, dtype="<U48")
    iterations = np.zeros(task.count, dtype=np.int32)
    objective = np.full(task.count, np.nan)
    solve_time = np.zeros(task.count)
    solve_cpu = np.zeros(task.count)
    for i, x in enumerate(s_in):
        try:
            r = solver.solve(x)
        except Exception as exc:  # a solver crash is a sample status, not the end of the run
            status[i] = f"Exception: {type(exc).__name__}"[:48]
            continue
        command[i], status[i], iterations[i] = r.command, r.status, r.iterations
        objective[i], solve_time[i], solve_cpu[i] = r.objective, r.solve_time, r.solve_cpu
    arrays = {"s_in": s_in, "command": command, "status": status, "iterations": iterations,
              "objective": objective}
    timing = {
        "solve_seconds": solve_time.tolist(),
        "solve_cpu_seconds": solve_cpu.tolist(),
        "wall_seconds": time.perf_counter() - start_wall,
        "cpu_seconds": time.process_time() - start_cpu,
        "worker": f"{socket.gethostname()}:{os.getpid()}",
    }
    return {"index": task.index, "arrays": arrays, "timing": timing}


# ----------------------------------------------------------------------------- shard files


def shard_paths(directory: Path, index: int) -> tuple[Path, Path]:
    stem = f"shard-{index:05d}"
    return directory / f"{stem}.npz", directory / f"{stem}.json"


def npz_bytes(arrays: dict) -> bytes:
    """An .npz (np.load reads it) whose bytes depend on the arrays only: fixed zip timestamps."""
    buffer = io.BytesIO()
    with zipfile.ZipFile(buffer, "w", compression=zipfile.ZIP_STORED) as zf:
        for name, value in arrays.items():
            member = io.BytesIO()
            np.lib.format.write_array(member, np.asarray(value), allow_pickle=False)
            info = zipfile.ZipInfo(f"{name}.npy", date_time=_FIXED_ZIP_TIME)
            info.external_attr = 0o644 << 16
            zf.writestr(info, member.getvalue())
    return buffer.getvalue()


def shard_statistics(arrays: dict) -> dict:
    """Solver statistics of one shard (deterministic: no timing)."""
    status, its = arrays["status"], arrays["iterations"]
    names, counts = np.unique(status, return_counts=True)
    ok = status == TRAINING_STATUS
    return {
        "status_counts": {str(k): int(v) for k, v in zip(names, counts)},
        "iterations_median": float(np.median(its)) if its.size else 0.0,
        "iterations_max": int(its.max()) if its.size else 0,
        "objective_median": float(np.median(arrays["objective"][ok])) if ok.any() else None,
    }


def write_shard(directory: Path, plan: DatasetPlan, result: dict) -> None:
    """npz first, then the sidecar that marks the shard finished; each atomically."""
    index, arrays = result["index"], result["arrays"]
    data = npz_bytes(arrays)
    npz_path, json_path = shard_paths(directory, index)
    atomic.write_bytes(npz_path, data)
    seed = shard_seed(plan.master_seed, index)
    sidecar = {
        "format": SHARD_FORMAT,
        "shard": index,
        "first_sample": index * plan.shard_size,
        "n_samples": int(arrays["s_in"].shape[0]),
        "seed": {"master_seed": plan.master_seed, "spawn_key": list(seed.spawn_key)},
        "config_hash": plan.config_hash(),
        "npz_sha256": hashlib.sha256(data).hexdigest(),
        "npz_bytes": len(data),
        "statistics": shard_statistics(arrays),
        "timing": result["timing"],
    }
    atomic.write_json(json_path, sidecar)


def read_shard(directory: Path, plan: "DatasetPlan", index: int) -> tuple[dict, dict]:
    """The arrays and sidecar of a finished shard; a damaged, foreign, swapped or edited shard is a
    HostError. The sidecar is bound to its place in the dataset (index, first sample, count, seeds,
    config hash), the npz to the sidecar (size, sha256), and the content to the index: the inputs
    must be the ones the shard's seed draws, and the statistics the ones its arrays give."""
    npz_path, json_path = shard_paths(directory, index)
    sidecar = read_json(json_path, "shard sidecar")
    config_hash, expected_count = plan.config_hash(), plan.shard_count(index)
    if sidecar.get("config_hash") != config_hash:
        raise HostError(f"{json_path}: config hash {str(sidecar.get('config_hash'))[:12]}… does not match "
                        f"the dataset's {config_hash[:12]}… (shard from another run; delete it or use another --out)")
    seed = shard_seed(plan.master_seed, index)
    place = {"format": SHARD_FORMAT, "shard": index, "first_sample": index * plan.shard_size,
             "n_samples": expected_count, "seed": {"master_seed": plan.master_seed, "spawn_key": list(seed.spawn_key)}}
    check_place(json_path, sidecar, place, index, "dataset")
    data = read_bound_npz(npz_path, json_path, sidecar)
    arrays = _load_npz(npz_path, data)
    if arrays["s_in"].shape[0] != expected_count:
        raise HostError(f"{npz_path}: {arrays['s_in'].shape[0]} samples, the dataset expects {expected_count}")
    if not np.array_equal(arrays["s_in"], draw_inputs(plan.master_seed, index, expected_count)):
        raise HostError(f"{npz_path}: its inputs are not the ones shard {index}'s seed draws (a swapped or edited "
                        f"shard); delete {npz_path.name} and {json_path.name} to recompute it")
    if sidecar.get("statistics") != shard_statistics(arrays):
        raise HostError(f"{json_path}: statistics differ from the ones its npz gives (an edited sidecar); "
                        f"delete it and its npz to recompute the shard")
    return arrays, sidecar


def _load_npz(path: Path, data: bytes) -> dict:
    try:
        with np.load(io.BytesIO(data), allow_pickle=False) as npz:
            arrays = {name: npz[name] for name in NPZ_ARRAYS}
    except (OSError, ValueError, KeyError, zipfile.BadZipFile, EOFError) as exc:
        raise HostError(f"{path}: not a valid shard npz ({type(exc).__name__})") from None
    m = arrays["s_in"].shape[0]
    for name, tail in NPZ_ARRAYS.items():
        if arrays[name].shape != (m, *tail):
            raise HostError(f"{path}: array {name} has shape {arrays[name].shape}, expected {(m, *tail)}")
    return arrays


def shard_is_finished(directory: Path, index: int) -> bool:
    return shard_paths(directory, index)[1].exists()


# ----------------------------------------------------------------------------- manifest


def open_dataset_dir(directory: Path, plan: DatasetPlan) -> None:
    """Create the directory and its manifest, or check that an existing one is the same plan."""
    manifest_path = directory / MANIFEST
    if manifest_path.exists():
        old = read_json(manifest_path, "dataset manifest")
        if old.get("config_hash") != plan.config_hash():
            raise HostError(f"{directory} holds a dataset of another configuration or OCP formulation "
                            f"(hash {str(old.get('config_hash'))[:12]}…); use another --out")
        if old.get("n_samples") != plan.n_samples:
            raise HostError(f"{directory} holds a dataset of N={old.get('n_samples')}, not {plan.n_samples}; "
                            "use the same --n or another --out")
        return
    atomic.write_json(manifest_path, plan.manifest())


def remove_stale_temporaries(directory: Path) -> None:
    """Temporary files of writes cut short by a kill (codegen.atomic names them .<name>.*.tmp)."""
    for path in directory.glob(".shard-*.tmp"):
        path.unlink(missing_ok=True)


def read_manifest(directory: Path) -> dict:
    path = Path(directory) / MANIFEST
    if not path.exists():
        raise HostError(f"{directory}: no {MANIFEST}; not a dataset made by `staregen samples`")
    manifest = read_json(path, "dataset manifest")
    if manifest.get("format") != DATASET_FORMAT:
        raise HostError(f"{path}: format {manifest.get('format')!r}, expected {DATASET_FORMAT!r}")
    return manifest


def plan_from_manifest(manifest: dict) -> DatasetPlan:
    ocp = dict(manifest["ocp"])
    ocp["extra_ipopt"] = tuple(tuple(kv) for kv in ocp.get("extra_ipopt", ()))
    return DatasetPlan(n_samples=manifest["n_samples"], ocp=OcpConfig(**ocp),
                       master_seed=manifest["master_seed"], shard_size=manifest["shard_size"])


# ----------------------------------------------------------------------------- the training side


def load_dataset(directory, include_failed: bool = False):
    """(X, Y, status, report) of a finished dataset; the contract is in docs/ocp.md.

    X (m, 12): S_in in Table 2 units; Y (m, 3): first optimal command, N·m; status (m,): IPOPT
    status strings; rows aligned. By default only the rows that pass TRAINING_RULE are
    returned; `include_failed=True` returns every row. A missing, corrupt or foreign shard
    raises HostError (never a silent partial dataset).
    """
    directory = Path(directory)
    manifest = read_manifest(directory)
    try:
        plan = plan_from_manifest(manifest)
    except (KeyError, TypeError, ValueError, AttributeError) as exc:   # a hand-edited manifest: fields missing or of other types
        raise HostError(f"{directory / MANIFEST}: malformed dataset manifest ({type(exc).__name__}: "
                        f"{str(exc)[:60]})") from None
    if plan.config_hash() != manifest.get("config_hash"):
        raise HostError(f"{directory / MANIFEST}: config hash does not match its own settings "
                        "(edited by hand, or made by another version of the OCP formulation or spacecraft model)")
    missing = [i for i in range(plan.n_shards) if not shard_is_finished(directory, i)]
    if missing:
        raise HostError(f"{directory}: dataset incomplete, {len(missing)} of {plan.n_shards} shards missing "
                        f"(first: shard-{missing[0]:05d}); rerun `staregen samples` with the same arguments")
    parts = [read_shard(directory, plan, i)[0] for i in range(plan.n_shards)]
    X = np.concatenate([p["s_in"] for p in parts])
    Y = np.concatenate([p["command"] for p in parts])
    status = np.concatenate([p["status"] for p in parts])
    iterations = np.concatenate([p["iterations"] for p in parts])
    usable = (status == TRAINING_STATUS) & np.all(np.isfinite(Y), axis=1)
    names, counts = np.unique(status[~usable], return_counts=True)
    report = {
        "directory": str(directory),
        "objective": plan.ocp.objective,
        "config_hash": plan.config_hash(),
        "ocp": plan.ocp.to_dict(),
        "n_shards": plan.n_shards,
        "n_total": int(status.size),
        "n_used": int(usable.sum()),
        "n_excluded": int((~usable).sum()),
        "excluded_by_status": {str(k): int(v) for k, v in zip(names, counts)},
        "rule": TRAINING_RULE,
        "iterations_median": float(np.median(iterations)),
        "iterations_max": int(iterations.max()),
    }
    keep = slice(None) if include_failed else usable
    return X[keep], Y[keep], status[keep], report


def timing_summary(directory) -> dict:
    """Per-sample solve times and per-shard worker times gathered from the sidecars."""
    directory = Path(directory)
    solve, solve_cpu, cpu, n = [], [], 0.0, 0
    for path in sorted(directory.glob("shard-*.json")):
        sidecar = read_json(path, "shard sidecar")
        solve.extend(sidecar["timing"]["solve_seconds"])
        solve_cpu.extend(sidecar["timing"]["solve_cpu_seconds"])
        cpu += sidecar["timing"]["cpu_seconds"]
        n += sidecar["n_samples"]
    wall_arr = np.asarray(solve) if solve else np.zeros(1)
    cpu_arr = np.asarray(solve_cpu) if solve_cpu else np.zeros(1)
    return {
        "samples": n,
        "solve_seconds_median": float(np.median(wall_arr)),
        "solve_seconds_p95": float(np.percentile(wall_arr, 95)),
        "solve_cpu_seconds_median": float(np.median(cpu_arr)),
        "worker_cpu_seconds_per_sample": cpu / n if n else 0.0,
    }


# ----------------------------------------------------------------------------- the client side


def finished_shards(directory: Path, plan: DatasetPlan) -> list[int]:
    """Indices of shards already finished; each is validated (a damaged one is a HostError)."""
    done = []
    for index in range(plan.n_shards):
        if shard_is_finished(directory, index):
            read_shard(directory, plan, index)
            done.append(index)
    return done


def create_dataset(directory, plan: DatasetPlan, scheduler: str | None = None, workers: int | None = None,
                   connect_timeout: float | None = None, processes: bool = True, progress: bool = True) -> dict:
    """Compute every unfinished shard of `plan` into `directory` on Dask; returns a run summary.

    The cluster is reached before anything is written, so a bad scheduler leaves no directory.
    """
    from host.learn.distributed import DEFAULT_CONNECT_TIMEOUT, dask_client, run_tasks

    plan.validate()
    directory = Path(directory)
    start = time.perf_counter()
    timeout = DEFAULT_CONNECT_TIMEOUT if connect_timeout is None else connect_timeout
    with dask_client(scheduler, workers, timeout, processes) as client:
        open_dataset_dir(directory, plan)
        remove_stale_temporaries(directory)
        kept = set(finished_shards(directory, plan))
        todo = [i for i in range(plan.n_shards) if i not in kept]
        tasks = [ShardTask(i, plan.shard_count(i), plan.master_seed, plan.ocp) for i in todo]
        n_workers = len(client.scheduler_info(n_workers=-1)["workers"])
        compute_start = time.perf_counter()
        for result in run_tasks(client, compute_shard, tasks, [t.count for t in tasks], "samples", progress):
            write_shard(directory, plan, result)
        compute = time.perf_counter() - compute_start
    wall = time.perf_counter() - start
    computed = sum(t.count for t in tasks)
    return {
        "directory": str(directory),
        "shards_total": plan.n_shards,
        "shards_kept": len(kept),
        "shards_computed": len(todo),
        "samples_computed": computed,
        "workers": n_workers,
        "wall_seconds": wall,
        "compute_seconds": compute,
        "samples_per_second": computed / compute if compute > 0 else 0.0,
    }
