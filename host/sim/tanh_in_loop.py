"""Paper 000's example with the generated tanh-law C in the loop: SIL (x86) or PIL (ARM emulator).

Every control period the plant state is rounded to float32 into the unit's input record, the C
step (tools.inloop, with the golden twin stepping alongside and compared bit for bit) returns
the torque, held for the period; the plant is host.plant.rigid_body as in host.sim.tanh_example. The run
is compared with the float64 sampled run of the same period (`run_in_loop`).
"""
from __future__ import annotations

import dataclasses
import math
import time
from dataclasses import dataclass
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from codegen import atomic  # noqa: E402
from codegen.unit import Batch  # noqa: E402
from codegen.units.tanh.emit import DEFAULT_PERIOD, INPUT_DTYPE  # noqa: E402
from codegen.units.tanh.unit import TanhUnit  # noqa: E402
from host.sim import tanh_example as ex  # noqa: E402
from host.errors import HostError  # noqa: E402
from host.plant.rigid_body import rows  # noqa: E402
from tools.inloop import InTheLoop  # noqa: E402

TARGETS = {"x86": "SIL x86", "arm": "PIL ARM emulator", "golden": "golden model"}


@dataclass
class _Law:
    """The fields of host.control.tanh_law.LawOutput that tanh_example's history records."""

    torque: tuple
    x1: tuple
    x2: tuple
    w_e: tuple
    status: int


def input_record(R_c, w_c, sc) -> np.ndarray:
    """The unit's input record of a plant state and the scenario's target (float32 rounding here)."""
    rec = np.zeros(1, dtype=INPUT_DTYPE)
    with np.errstate(over="ignore"):
        rec["R_c"], rec["w_c"] = np.ravel(R_c), w_c
        rec["R_t"], rec["w_t"], rec["wdot_t"] = np.ravel(sc.R_t), sc.w_t, sc.wdot_t
    return rec


def simulate_in_loop(sc, target: str, period: float, duration: float, dt: float) -> dict:
    """host.sim.tanh_example.simulate_sampled with the generated step as the law. Returns the history
    plus `golden_mismatch_steps`, `records` (state before, input of every step) and, for PIL,
    `cycles` (per step, ideal memory)."""
    loop = InTheLoop(TanhUnit(sc.params, period), target)
    result = fly(sc, loop.step, period, duration, dt)
    inputs, _ = loop.trace()
    result.update({"golden_mismatch_steps": loop.mismatch_steps, "records": Batch(loop.state_records(), inputs)})
    if target == "arm":
        result["cycles"] = np.array(loop.cycles, dtype=np.int64)
    return result


def fly(sc, step, period: float, duration: float, dt: float) -> dict:
    """The sampled example with `step(input record) -> output record` as the law (the unit in the loop,
    or a flight package's own `<name>_tanh_step`): the history, R_c_final and control_steps."""
    body = ex.plant(sc)
    c = ex.compile_constants(sc.params)
    n_ctrl, n_sub = ex.step_count(duration, period), ex.step_count(period, dt)
    h = period / n_sub
    hist = ex.History(n_ctrl * n_sub + 1)
    y = ex.initial_state(sc)
    for kk in range(n_ctrl + 1):
        row = step(input_record(rows(y), y[9:12], sc))[0]
        _, w_e = ex.true_errors(c, sc, y)
        out = _Law(tuple(map(float, row["torque"])), tuple(map(float, row["x1"])), tuple(map(float, row["x2"])),
                   w_e, int(row["status"]))
        varpi = tuple(map(float, row["varpi"]))
        if kk == n_ctrl:
            hist.add(n_ctrl * period, out, varpi)
            break
        for j in range(n_sub):
            t = kk * period + j * h
            if j:
                hist.add(t, out, varpi, *ex.true_errors(c, sc, y))
            else:
                hist.add(t, out, varpi)
            y = body.rk4_step(t, y, h, out.torque)
    return {**hist.as_dict(), "R_c_final": np.array(rows(y)), "control_steps": n_ctrl + 1}


def run_in_loop(target: str, period: float = DEFAULT_PERIOD, duration: float = 40.0, dt: float = 5e-4,
                out_dir=None, reference: dict | None = None) -> dict:
    """The paper-000 example with the C in the loop (target "x86" = SIL, "arm" = PIL), compared
    with the float64 sampled run at the same period: metrics as host.sim.tanh_example.run plus
    `e_diff_max` (max |‖e‖_C − ‖e‖_float64| over the run), `e_diff_after_25s`, `t_e_diff_above_1e-6`,
    `golden_mismatch_steps`, and for PIL `cycles_min/median/max` of tanh_step."""
    if target not in TARGETS:
        raise HostError(f"unknown C target {target!r} (x86 or arm)")
    if not (period > 0 and math.isfinite(period)):
        raise HostError(f"control period must be > 0 s, got {period!r}")
    sc = ex.paper_scenario()
    start = time.perf_counter()
    history = simulate_in_loop(sc, target, period, duration, dt)
    runtime = time.perf_counter() - start
    ref = reference if reference is not None else ex.simulate_sampled(sc, period, duration, dt)
    metrics = ex.metrics_of(history)
    e_c = np.linalg.norm(history["e"], axis=1)
    e_64 = np.linalg.norm(ref["e"], axis=1)
    if e_c.shape != e_64.shape:
        raise HostError("C and float64 runs have different lengths (internal error)")
    diff = np.abs(e_c - e_64)
    # The yardstick for diff: the float64 run itself, started from w_c(0) rounded to float32 (what
    # any float32 interface does to the state), moves by this much (docs/tanh-controller.md).
    sc32 = dataclasses.replace(sc, w_c0=tuple(float(np.float32(w)) for w in sc.w_c0))
    self_diff = np.abs(np.linalg.norm(ex.simulate_sampled(sc32, period, duration, dt)["e"], axis=1) - e_64)
    late = history["t"] >= 25.0
    metrics.update({
        "mode": f"sampled, C in the loop ({'SIL x86' if target == 'x86' else 'PIL ARM emulator'})",
        "target": target, "period": float(period), "dt": float(dt), "duration": float(duration),
        "settle_threshold": ex.SETTLE_THRESHOLD, "runtime_s": round(runtime, 3),
        "control_steps": history["control_steps"], "golden_mismatch_steps": history["golden_mismatch_steps"],
        "e_diff_max": float(diff.max()), "e_diff_after_25s": float(diff[late].max()) if late.any() else None,
        "t_e_diff_above_1e-6": float(history["t"][np.argmax(diff > 1e-6)]) if (diff > 1e-6).any() else None,
        "t_settle_float64": ex.metrics_of(ref)["t_settle"], "e_final_float64": float(e_64[-1]),
        "e_diff_float64_self_max": float(self_diff.max()),
        "parameters": sc.params.to_mapping(),
    })
    if "cycles" in history:
        cyc = history["cycles"]
        metrics.update({"cycles_min": int(cyc.min()), "cycles_median": int(np.median(cyc)),
                        "cycles_max": int(cyc.max())})
    if out_dir is not None:
        ex.write_outputs(Path(out_dir), metrics, history)
        _plot_c_vs_float64(Path(out_dir) / "fig_c_vs_float64.png", history["t"], diff, self_diff, metrics)
    return {**metrics, "metrics": metrics, "history": history, "reference": ref}


def _plot_c_vs_float64(path: Path, t: np.ndarray, diff: np.ndarray, self_diff: np.ndarray, metrics: dict) -> None:
    """|‖e‖_C − ‖e‖_float64| over the run, beside the float64 run's own change from a float32-rounded
    w_c(0), on a log scale with the 1e-6 line of issue 7."""
    fig, ax = plt.subplots(figsize=(8, 4.5))
    ax.semilogy(t, np.maximum(diff, 1e-16), label=f"C ({metrics['target']}) vs float64 sampled run")
    ax.semilogy(t, np.maximum(self_diff, 1e-16), label="float64 run from w_c(0) rounded to float32 vs float64", alpha=0.8)
    ax.axhline(1e-6, color="k", lw=0.8, ls="--", label="1e-6")
    ax.set_xlabel("t (s)")
    ax.set_ylabel("|Δ‖e‖| (-)")
    ax.set_title(f"tanh law, sampled T = {metrics['period']} s: the C against the float64 run")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(loc="lower left", fontsize=8)
    fig.tight_layout()
    with atomic.writing(path, suffix=".png") as tmp:
        fig.savefig(tmp, format="png", dpi=110)
    plt.close(fig)


def example_records(params, period: float = DEFAULT_PERIOD, duration: float = 40.0) -> Batch:
    """(state before, input) of every step the law takes on the paper-000 example (golden model)."""
    sc = ex.paper_scenario(params=params)
    return simulate_in_loop(sc, "golden", period, duration, ex.MAX_REFERENCE_STEP)["records"]
