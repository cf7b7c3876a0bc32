"""The training sweep of paper 001 Table 3 on Dask: activation × hidden size × epochs, selected by test MSE.

Every net is trained on the same seeded 75/25 split with the same recipe and seed (host.learn.training);
the data are scattered to the workers once. The winner is the net with the smallest test MSE
(mean normalised, i.e. eq. 24 / (3 N_test): the same order as eq. 24 on a fixed split), as the
paper selects. Only tansig can fly (the artifact and the flight C implement tanh only): when
another activation wins it is reported and the best tansig net is exported, and the artifact's
metadata says so. The exported net is retrained on the client by host.learn.training.train_artifact
with the chosen size and epochs (training is deterministic, so it is the net the worker scored).
"""
from __future__ import annotations

import time
from dataclasses import asdict, dataclass
from pathlib import Path

import dask

from host.learn import training
from host.learn.distributed import dask_client, run_tasks
from host.errors import HostError
from codegen import atomic

FULL_ACTIVATIONS = ("tansig", "logsig", "sigmoid", "relu")
FULL_HIDDEN = tuple(range(10, 61))
FULL_EPOCHS = tuple(range(100, 1001, 50))
REDUCED_ACTIVATIONS = ("tansig", "logsig", "relu")
REDUCED_HIDDEN = (20, 40, 60)
REDUCED_EPOCHS = (200, 700)
# Dask's nanny starts workers with MALLOC_TRIM_THRESHOLD_ set, which (mallopt(3)) switches off
# glibc's dynamic mmap threshold: every buffer >= 128 KiB is then mmapped and unmapped again, and
# torch allocates MB-sized ones at every step. Measured on one 12-40-3 net: 1.7 M page faults and
# 2.6 s of system time on 4.3 s of user time; with a 32 MiB mmap threshold 0.26 M and 0.7 s.
LOCAL_WORKER_CONFIG = {"distributed.nanny.pre-spawn-environ.MALLOC_MMAP_THRESHOLD_": 1 << 25}
SELECTED_BY = "minimum test MSE (mean over 3 x N_test normalised squared errors; same order as eq. 24)"


@dataclass(frozen=True, order=True)
class SweepPoint:
    activation: str
    hidden: int
    epochs: int


def grid(full: bool = False) -> list[SweepPoint]:
    """Table 3's 4 × 51 × 19 = 3,876 points, or the reduced 3 × 3 × 2 = 18."""
    acts, hidden, epochs = ((FULL_ACTIVATIONS, FULL_HIDDEN, FULL_EPOCHS) if full
                            else (REDUCED_ACTIVATIONS, REDUCED_HIDDEN, REDUCED_EPOCHS))
    return [SweepPoint(a, h, e) for a in acts for h in hidden for e in epochs]


def train_point(task: dict) -> dict:
    """Worker side: train one grid point on the scattered data and score it on the test split."""
    X, Y = task["data"]
    point: SweepPoint = task["point"]
    recipe = training.recipe_named(task["recipe"], point.epochs)
    split = training.make_split(X, Y, task["seed"])
    try:
        fit = training.fit_network(split, point.activation, point.hidden, recipe, task["seed"])
    except HostError as exc:  # a diverged net is a result of the sweep, not the end of it
        return {**asdict(point), "error": str(exc)}
    metrics = training.error_metrics(split.Y_test, training.predict_physical(fit, split, split.X_test),
                                     split.output_map)
    return {**asdict(point), **metrics, "train_mse_normalised": fit.train_mse_normalised,
            "train_seconds": fit.train_seconds}


def _rank_key(result: dict):
    mse = result.get("mse_mean_normalised")
    return (mse is None, mse or 0.0, FULL_ACTIVATIONS.index(result["activation"]), result["hidden"], result["epochs"])


def select(results: list[dict]) -> tuple[dict, dict | None]:
    """(best overall, best tansig or None), by test MSE; ties broken by activation, size, epochs.
    Diverged nets (an "error" entry) are never selected."""
    ranked = sorted((r for r in results if "error" not in r), key=_rank_key)
    if not ranked:
        raise HostError(f"all {len(results)} nets of the sweep diverged (first: {results[0]['error']})")
    tansig = [r for r in ranked if r["activation"] == training.EXPORTABLE_ACTIVATION]
    return ranked[0], (tansig[0] if tansig else None)


def _record(result: dict) -> dict:
    """A result without its timing, for the artifact (whose bytes must not depend on the run)."""
    return {k: v for k, v in result.items() if k != "train_seconds"}


def choice_of(results: list[dict], full: bool, recipe: str) -> dict:
    best, best_tansig = select(results)
    if best_tansig is None:
        raise HostError("the sweep grid holds no tansig net; only tansig can be exported to flight C")
    exported = ("the overall best" if best is best_tansig else
                f"the best tansig net: {best['activation']} won the sweep but only tansig can be exported to flight C")
    return {"grid": "full (Table 3)" if full else "reduced", "n_networks": len(results),
            "n_diverged": sum("error" in r for r in results), "recipe": recipe,
            "selected_by": SELECTED_BY, "best_overall": _record(best), "best_tansig": _record(best_tansig),
            "exported": exported}


@dataclass
class SweepResult:
    results: list               # one dict per net, ranked best first
    choice: dict
    artifact: object
    report: training.TrainReport
    wall_seconds: float
    workers: int


def train_grid(X, Y, points, recipe: str, seed: int, scheduler, workers, progress: bool,
               connect_timeout: float) -> tuple[list[dict], int]:
    """(each point's result dict, in finishing order; the number of Dask workers)."""
    import distributed  # noqa: F401 -- load its config defaults first: leaving dask.config.set()
    #                   would otherwise drop the whole "distributed" section that set() created
    points = sorted(points, key=lambda p: (-p.hidden * p.epochs, p))  # costliest first: short ones end the run
    with dask.config.set(LOCAL_WORKER_CONFIG), \
            dask_client(scheduler, workers, connect_timeout=connect_timeout) as client:
        n_workers = len(client.scheduler_info().get("workers", {}))
        shared = client.scatter((X, Y), broadcast=True)  # the data travel once per worker
        tasks = [{"point": p, "data": shared, "recipe": recipe, "seed": seed} for p in points]
        results = list(run_tasks(client, train_point, tasks, [1] * len(tasks), desc="sweep (networks)",
                                 progress=progress))
    return results, n_workers


def run_sweep(data, full: bool = False, recipe: str = "default", seed: int = 0, scheduler: str | None = None,
              workers: int | None = None, points: list[SweepPoint] | None = None, progress: bool = True,
              connect_timeout: float = 10.0) -> SweepResult:
    """Train every grid point on Dask, select, and export the best tansig net (retrained on the client)."""
    start = time.perf_counter()
    X, Y, dataset_report = training.load_training_data(data)
    points = points if points is not None else grid(full)
    X, Y = training.check_samples(X, Y, max(p.hidden for p in points))
    training.recipe_named(recipe)  # a bad name fails before the cluster starts
    results, n_workers = train_grid(X, Y, points, recipe, seed, scheduler, workers, progress, connect_timeout)
    results.sort(key=_rank_key)
    choice = choice_of(results, full, recipe)
    best = choice["best_tansig"]
    artifact, report = training.train_artifact((X, Y, dataset_report), recipe=recipe, seed=seed,
                                               epochs=best["epochs"], hidden=best["hidden"], choice=choice)
    return SweepResult(results, choice, artifact, report, time.perf_counter() - start, n_workers)


def markdown(sweep: SweepResult) -> str:
    c = sweep.choice
    best, tansig = c["best_overall"], c["best_tansig"]
    lines = [f"# Training sweep ({c['grid']}, {c['n_networks']} nets, {c['recipe']} recipe)", "",
             f"Selected by {c['selected_by']}.", "",
             f"* best overall: {best['activation']} {best['hidden']} hidden, {best['epochs']} epochs, "
             f"test MSE {best['mse_mean_normalised']:.4g}",
             f"* exported: {c['exported']} — tansig {tansig['hidden']} hidden, {tansig['epochs']} epochs, "
             f"test MSE {tansig['mse_mean_normalised']:.4g}",
             f"* wall time {sweep.wall_seconds:.1f} s on {sweep.workers} workers", "",
             "| rank | activation | hidden | epochs | test MSE (mean, normalised) | eq. 24 sum | relative torque "
             "error | train MSE | train s |", "|---|---|---|---|---|---|---|---|---|"]
    for rank, r in enumerate(sweep.results, 1):
        if "error" in r:
            lines.append(f"| {rank} | {r['activation']} | {r['hidden']} | {r['epochs']} | diverged | | | | |")
            continue
        lines.append(f"| {rank} | {r['activation']} | {r['hidden']} | {r['epochs']} | {r['mse_mean_normalised']:.4g} "
                     f"| {r['mse_eq24_sum_normalised']:.4g} | {100 * r['relative_torque_error']:.3f} % "
                     f"| {r['train_mse_normalised']:.4g} | {r['train_seconds']:.1f} |")
    return "\n".join(lines) + "\n"


def prepare_out_dir(out) -> Path:
    """Create the output folder now, so an unwritable one fails before hours of training."""
    out = Path(out)
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise HostError(f"{out}: cannot create the sweep folder ({exc.strerror or exc})") from None
    training.check_writable(out / "model.json")
    return out


def write_sweep(sweep: SweepResult, out) -> dict[str, Path]:
    """sweep.json (every net, the choice, timings), sweep.md (the table) and model.json (the artifact)."""
    out = Path(out)
    doc = {"choice": sweep.choice, "results": sweep.results, "wall_seconds": sweep.wall_seconds,
           "workers": sweep.workers, "exported_artifact_sha256": sweep.artifact.sha256,
           "exported_test_metrics": sweep.report.net, "baselines": sweep.report.baselines}
    try:
        paths = {"json": atomic.write_json(out / "sweep.json", doc),
                 "markdown": atomic.write_text(out / "sweep.md", markdown(sweep))}
    except OSError as exc:
        raise HostError(f"{out}: cannot write the sweep results ({exc.strerror or exc})") from None
    paths["artifact"] = training.save_artifact(sweep.artifact, out / "model.json")
    return paths
