"""Accuracy of the discrete-point law on the network's train/test split (seed paper 003's Table 3
measure beside ours), over a grid of r × S_limit, with the 12-40-3 network and the fitted
baselines on the same test samples (docs/discrete-point.md)."""
from __future__ import annotations

import time
from dataclasses import dataclass, replace

import numpy as np

from codegen import artifact as art
from host.control.baselines import LinearLS, SaturatedLinear
from host.control.discrete_point import DpParams, DpModel
from host.control.nn_controller import network64
from host.errors import HostError
from host.learn import training as tr


@dataclass(frozen=True)
class Accuracy:
    label: str
    mean_abs_error: float          # paper 003 Table 3: mean of |Ô − O| over every test element, N·m
    relative_torque_error: float   # ||Ô − O||_F / ||O||_F (training.RELATIVE_ERROR_DEFINITION)
    max_abs_error: float           # N·m
    widened: float | None = None   # share of test queries that needed a box wider than level 0
    every_sample: float | None = None  # share that fell through to every sample
    found_median: float | None = None  # points in the used box (before S_limit), median
    seconds: float | None = None   # host wall time for the whole test set


def measure(label: str, Y_true: np.ndarray, Y_pred: np.ndarray, **extra) -> Accuracy:
    err = Y_pred - Y_true
    return Accuracy(label, float(np.mean(np.abs(err))), float(np.linalg.norm(err) / np.linalg.norm(Y_true)),
                    float(np.max(np.abs(err))), **extra)


def dp_accuracy(split: tr.Split, config: DpParams) -> Accuracy:
    t0 = time.perf_counter()
    model = DpModel.fit(split.X_train, split.Y_train, config)
    results = [model.query(q) for q in split.X_test]
    seconds = time.perf_counter() - t0
    levels = np.array([r.level for r in results])
    last = len(config.sides())
    return measure(f"discrete point r = {config.r:g}, S_limit = {config.s_limit}",
                   split.Y_test, np.array([r.torque for r in results]),
                   widened=float(np.mean(levels > 0)), every_sample=float(np.mean(levels == last)),
                   found_median=float(np.median([r.found for r in results])), seconds=seconds)


def network_accuracy(a: art.Artifact, split: tr.Split, X: np.ndarray, Y: np.ndarray, seed: int) -> Accuracy:
    """The artifact on the test split, refused unless it was trained on these samples with this seed."""
    meta = a.metadata or {}
    if meta.get("dataset_sha256") != tr.dataset_sha256(X, Y) or meta.get("seed") != seed:
        raise HostError("the network was not trained on this dataset with this split seed (its metadata's "
                        "dataset_sha256 / seed differ); train it with `staregen train --data` on the same folder")
    pred = np.array([network64(a, x) for x in split.X_test])
    return measure(f"network {a.n_in}-{a.n_hidden}-{a.n_out} tansig", split.Y_test, pred)


def sweep(X: np.ndarray, Y: np.ndarray, rs: tuple[float, ...], s_limits: tuple[int, ...], base: DpParams,
          network: art.Artifact | None = None, seed: int = 0, bound: float | None = None,
          progress=None) -> list[Accuracy]:
    """Rows: the network (if given), PD + feed-forward (saturated at the dataset's torque `bound`, as
    `staregen train` fits it), linear LS, then every (r, S_limit)."""
    split = tr.make_split(X, Y, seed)
    rows = []
    if network is not None:
        rows.append(network_accuracy(network, split, X, Y, seed))
    rows.append(measure("PD + feed-forward (saturated linear)", split.Y_test,
                        SaturatedLinear.fit(split.X_train, split.Y_train, bound).predict(split.X_test)))
    rows.append(measure("linear least squares", split.Y_test,
                        LinearLS.fit(split.X_train, split.Y_train).predict(split.X_test)))
    configs = [replace(base, r=r, s_limit=s, n_min=min(base.n_min, s)).validate() for r in rs for s in s_limits]
    for c in configs:
        rows.append(dp_accuracy(split, c))
        if progress is not None:
            progress()
    return rows


def markdown(rows: list[Accuracy]) -> str:
    head = ("| model | mean abs error [N·m] (paper 003 Table 3) | relative torque error | max abs error [N·m] | "
            "widened | every sample | points found (median) | host s |\n|---|---:|---:|---:|---:|---:|---:|---:|")

    def opt(x, f):
        return "" if x is None else f.format(x)
    body = [f"| {r.label} | {r.mean_abs_error:.3e} | {100 * r.relative_torque_error:.3f} % | {r.max_abs_error:.3g} | "
            f"{opt(r.widened, '{:.0%}')} | {opt(r.every_sample, '{:.0%}')} | {opt(r.found_median, '{:.0f}')} | "
            f"{opt(r.seconds, '{:.1f}')} |" for r in rows]
    return "\n".join([head, *body])
