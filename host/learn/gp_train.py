"""Paper 004's trained GP for the takeover law (docs/gp-takeover.md §3, §4, §7; `staregen gp train`).

One run: §3's data (training pool = the PD-excited runs of `train_seeds`, held-out test = those of
`test_seeds`), the sparse GP (shared Z, k-means++ initialised) trained on the whole pool, and in the
output folder:

- `gp.json`: the sealed artifact (host.learn.gp.artifact_from) with metadata: the pool's sha256
  (`dataset_sha256`: x (N×9) then d (N×3), float64 little-endian, C order), held-out test MSE per
  axis, training time, n_train, M, iterations, seed;
- `gp_law.toml`: the law's file (codegen.units.gp.params.load_params reads it; §5 gains, 1 N·m,
  J_s = Table 6) naming `gp.json`;
- `train.json`: train and test MSE and R² per axis, the mean predicted standard deviation (latent +
  noise) against the RMS of the actual error, the 95 % band's coverage, times;
- `fig2_gp_response.png` and `fig3_gp_error.png`: the paper's Figs. 2-3 on the first test run (d
  against the GP mean with the 95 % band, ±1.96 √(σ² + noise); the absolute regression error).
"""
from __future__ import annotations

import hashlib
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Callable

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from codegen import atomic  # noqa: E402
from codegen.units.gp import artifact as gpa  # noqa: E402
from codegen.units.gp.params import GpLawParams, load_params  # noqa: E402
from host.control import takeover_laws as laws  # noqa: E402
from host.learn import gp  # noqa: E402
from host.plant.spacecraft import TABLE6_INERTIA  # noqa: E402
from host.sim.plots import save_figure  # noqa: E402
from host.sim.takeover import RUN_DURATION, collect  # noqa: E402

ARTIFACT_NAME = "gp.json"
LAW_NAME = "gp_law.toml"
SUMMARY_NAME = "train.json"
FIGURE_RESPONSE = "fig2_gp_response.png"
FIGURE_ERROR = "fig3_gp_error.png"
BAND = 1.96                      # 95 % two-sided, Gaussian
AXES = ("x", "y", "z")

Log = Callable[[str], None]


@dataclass(frozen=True)
class Dataset:
    x: np.ndarray          # N×9 raw inputs
    d: np.ndarray          # N×3 N·m
    seed: np.ndarray       # N, the run each sample comes from
    t: np.ndarray          # N, s within its run


@dataclass
class Trained:
    fit: gp.GpFit
    artifact: gpa.GpArtifact
    summary: dict
    pool: Dataset
    test: Dataset


def _quiet(_line: str) -> None:
    return None


def collect_runs(seeds, duration: float = RUN_DURATION, label: str = "runs", log: Log = _quiet) -> Dataset:
    """§3's samples of one excited run per seed, stacked in seed order (progress per run)."""
    parts = []
    seeds = list(seeds)
    for i, seed in enumerate(seeds):
        start = time.perf_counter()
        parts.append(collect([seed], duration))
        log(f"  {label}: run {i + 1}/{len(seeds)} (seed {seed}, {duration:g} s) "
            f"{len(parts[-1]['t'])} samples, {time.perf_counter() - start:.1f} s")
    return Dataset(*(np.concatenate([p[k] for p in parts]) for k in ("x", "d", "seed", "t")))


def dataset_sha256(x: np.ndarray, d: np.ndarray) -> str:
    """sha256 of the pool: x then d, float64 little-endian, C order."""
    h = hashlib.sha256()
    for a in (x, d):
        h.update(np.ascontiguousarray(a, dtype="<f8").tobytes())
    return h.hexdigest()


def regression_stats(fit: gp.GpFit, x: np.ndarray, d: np.ndarray) -> dict:
    """MSE and R² per axis, the predicted standard deviation (latent + noise) against the RMS error, the
    share of samples inside the 95 % band."""
    mean, var = fit.predict(x, noise=True)
    err = mean - d
    m = gp.mse(mean, d)
    std = np.sqrt(var)
    return {"n": int(len(x)), "mse": m["mse"], "mse_per_axis": m["per_axis"],
            "r2_per_axis": [1.0 - v for v in m["normalised"]],
            "rms_error_per_axis": np.sqrt(np.mean(err ** 2, axis=0)).tolist(),
            "mean_predicted_std_per_axis": np.mean(std, axis=0).tolist(),
            "band95_coverage_per_axis": np.mean(np.abs(err) <= BAND * std, axis=0).tolist()}


def train(pool: Dataset, test: Dataset, m: int = gp.DEFAULT_M, iterations: int = gp.SPARSE_ITERATIONS,
          seed: int = 0, log: Log = _quiet) -> Trained:
    """The sparse GP on the whole pool, its artifact (metadata of §7) and the summary of train.json."""
    log(f"training the sparse GP: M = {m}, {iterations} Adam iterations, {len(pool.x)} samples, seed {seed}")
    fit = gp.train_sparse(pool.x, pool.d, m=m, iterations=iterations, seed=seed)
    log(f"  trained in {fit.train_time_s:.1f} s (k-means {fit.kmeans_time_s:.2f} s), final loss {fit.losses[-1]:.4g}")
    train_stats, test_stats = regression_stats(fit, pool.x, pool.d), regression_stats(fit, test.x, test.d)
    meta = {"dataset_sha256": dataset_sha256(pool.x, pool.d), "test_mse": test_stats["mse_per_axis"],
            "train_time_s": round(fit.train_time_s, 3), "n_train": int(len(pool.x)), "m": int(m),
            "iterations": int(iterations), "seed": int(seed),
            "train_seeds": sorted({int(s) for s in pool.seed}), "test_seeds": sorted({int(s) for s in test.seed})}
    artifact = gp.artifact_from(fit, meta)
    summary = {"m": int(m), "iterations": int(iterations), "seed": int(seed), "n_train": int(len(pool.x)),
               "n_test": int(len(test.x)), "train_seeds": meta["train_seeds"], "test_seeds": meta["test_seeds"],
               "dataset_sha256": meta["dataset_sha256"], "train_time_s": fit.train_time_s,
               "kmeans_time_s": fit.kmeans_time_s, "final_loss": fit.losses[-1], "train": train_stats,
               "test": test_stats, "artifact_sha256": artifact.sha256,
               "cond_kzz": artifact.conditioning.cond}
    return Trained(fit, artifact, summary, pool, test)


# ----------------------------------------------------------------------------- the law's file


def law_toml(artifact_name: str = ARTIFACT_NAME, inertia=TABLE6_INERTIA) -> str:
    """The law's parameter file (codegen.units.gp.params): §5 gains, torque limit, J_s."""
    rows = ", ".join("[" + ", ".join(repr(float(v)) for v in row) + "]" for row in np.asarray(inertia))
    return (f"# Paper 004's GP takeover law (docs/gp-takeover.md section 5): written by `staregen gp train`.\n"
            f"artifact = \"{artifact_name}\"          # relative to this file's folder\n"
            f"k1 = {laws.K1!r}                  # N*m,        K1(s) = k1 + (k1_bar - k1) s\n"
            f"k1_bar = {laws.K1_BAR!r}\n"
            f"k2 = {laws.K2!r}                 # N*m*s/rad,  K2(s) = k2 + (k2_bar - k2) s\n"
            f"k2_bar = {laws.K2_BAR!r}\n"
            f"torque_max = {laws.TORQUE_MAX!r}          # N*m per axis\n"
            f"inertia = [{rows}]   # kg*m^2, J_s (paper 001 Table 6)\n")


def write_outputs(folder: Path, trained: Trained) -> GpLawParams:
    """gp.json, gp_law.toml, train.json and the two figures into `folder`; the law's file is read back
    (load_params) and its parameters returned: a file the law cannot read is an error here."""
    trained.artifact.save(folder / ARTIFACT_NAME)
    atomic.write_text(folder / LAW_NAME, law_toml())
    params = load_params(folder / LAW_NAME)
    atomic.write_json(folder / SUMMARY_NAME, {**trained.summary, "law_sha256": params.sha256()})
    run = int(trained.test.seed[0])
    sel = trained.test.seed == run
    mean, var = trained.fit.predict(trained.test.x[sel], noise=True)
    t, d = trained.test.t[sel], trained.test.d[sel]
    save_figure(response_figure(t, d, mean, var, run, trained.summary), folder / FIGURE_RESPONSE)
    save_figure(error_figure(t, d, mean, run, trained.summary), folder / FIGURE_ERROR)
    return params


def response_figure(t, d, mean, var, run: int, summary: dict):
    """Fig. 2: d (measured, §3) against the GP mean and the 95 % band, per axis."""
    fig, axes = plt.subplots(3, 1, figsize=(8, 7), sharex=True)
    half = BAND * np.sqrt(var)
    for i, ax in enumerate(axes):
        ax.fill_between(t, mean[:, i] - half[:, i], mean[:, i] + half[:, i], color="C1", alpha=0.25,
                        label="95 % band (±1.96 √(σ² + noise))")
        ax.plot(t, d[:, i], "k.", ms=2.5, label="d (measured)")
        ax.plot(t, mean[:, i], color="C1", lw=1.0, label="GP mean μ")
        ax.set_ylabel(f"d_{AXES[i]} (N·m)")
        ax.grid(True, alpha=0.3)
    axes[0].set_title(f"GP response on held-out run (seed {run}), M = {summary['m']} (paper's Fig. 2)")
    axes[0].legend(loc="upper right", fontsize=7)
    axes[-1].set_xlabel("t (s)")
    fig.tight_layout()
    return fig


def error_figure(t, d, mean, run: int, summary: dict):
    """Fig. 3: |μ − d| per axis."""
    fig, axes = plt.subplots(3, 1, figsize=(8, 6), sharex=True)
    for i, ax in enumerate(axes):
        ax.plot(t, np.abs(mean[:, i] - d[:, i]), lw=0.8)
        ax.set_ylabel(f"|μ_{AXES[i]} − d_{AXES[i]}| (N·m)")
        ax.grid(True, alpha=0.3)
    mse = ", ".join(f"{v:.2e}" for v in summary["test"]["mse_per_axis"])
    axes[0].set_title(f"Absolute regression error, seed {run} (paper's Fig. 3); test MSE per axis {mse} (N·m)²")
    axes[-1].set_xlabel("t (s)")
    fig.tight_layout()
    return fig


__all__ = ["Dataset", "Trained", "collect_runs", "dataset_sha256", "regression_stats", "train", "law_toml",
           "write_outputs", "ARTIFACT_NAME", "LAW_NAME", "SUMMARY_NAME", "FIGURE_RESPONSE", "FIGURE_ERROR"]
