"""Paper 002's tracking scenario flown by the RBF law: float64, or the generated unit in the loop
(SIL x86 / PIL ARM emulator), with its metrics beside the paper's 22.9 s and 5.7 s, and figures.

`run(controller, params, ...)`: controller "rbf" (host.control.rbf_law, float64), "rbf-c" (the
generated C through cffi) or "rbf-arm" (the ARM ELF in the emulator, cycles of every step). The C
runs are also gates: the golden twin steps alongside (tools.inloop) and every output and state
word is compared. They are compared with the float64 run of the same parameters and period:
the largest range and attitude differences over the run and the metric differences.
"""
from __future__ import annotations

import math
import time
from pathlib import Path
from types import SimpleNamespace

import numpy as np

from codegen import atomic
from codegen.units.rbf.params import RbfParams
from host.core.constants import DEG
from host.errors import HostError
from host.sim import rbf_tracking
from host.sim.plots import stacked_figure as _figure
from host.sim.scenarios import configure_unit
from tools.inloop import InTheLoop

CONTROLLERS = {"rbf": None, "rbf-c": "x86", "rbf-arm": "arm"}
TARGET_NAMES = {"x86": "SIL x86", "arm": "PIL ARM emulator"}
PAPER = {"t_approach_s": 22.9, "t_attitude_s": 5.7}     # paper 002, section 3.2
HISTORY_KEYS = ("t", "los", "los_d", "e1", "force", "torque", "force_applied", "torque_applied", "w_hat",
                "w_true", "status")


class UnitController:
    """The generated unit in the loop as a closed-loop controller; `state` exposes the weights (the
    golden twin's, equal to the C's word for word while no step mismatches) for the history."""

    def __init__(self, loop: InTheLoop, nodes: int):
        self.loop, self.nodes = loop, nodes
        self._step = rbf_tracking.record_controller(loop.step)

    def __call__(self, m):
        return self._step(m)

    @property
    def state(self) -> SimpleNamespace:
        record = (self.loop.twin or self.loop.run).state[0]
        return SimpleNamespace(theta=record["theta"].reshape(self.nodes, 6).astype(float),
                               theta_delta=record["theta_delta"].reshape(self.nodes, 6).astype(float))


def simulate(controller: str, params: RbfParams, duration: float, period: float, dt: float) -> dict:
    """History of one closed loop; for the C: `golden_mismatch_steps` and (PIL) `cycles`."""
    target = CONTROLLERS[controller]
    if target is None:
        return rbf_tracking.simulate(params, duration, period=period, dt=dt)
    loop = InTheLoop(configure_unit("rbf", params=params, period=period), target)
    hist = rbf_tracking.simulate(params, duration, controller=UnitController(loop, params.nodes), period=period,
                                 dt=dt)
    hist["golden_mismatch_steps"] = np.int64(loop.mismatch_steps)
    if target == "arm":
        hist["cycles"] = np.array(loop.cycles, dtype=np.int64)
    return hist


def _diff_to(reference: dict, hist: dict) -> dict:
    """Largest differences of the C run from the float64 run (same instants)."""
    d_rho = np.abs(hist["los"][:, 0] - reference["los"][:, 0])
    d_att = np.abs(hist["e1"][:, 3:] - reference["e1"][:, 3:]) / DEG
    return {"max_rho_diff_m": float(d_rho.max()), "max_attitude_diff_deg": float(d_att.max()),
            "max_force_diff_n": float(np.nanmax(np.abs(hist["force"] - reference["force"])))}


def run(controller: str, params: RbfParams, duration: float = 1000.0, period: float = rbf_tracking.PERIOD,
        dt: float = rbf_tracking.DT, out_dir: Path | None = None) -> dict:
    """Metrics (and, with out_dir, metrics.json, history.npz and figures) of one controller."""
    if controller not in CONTROLLERS:
        raise HostError(f"unknown controller {controller!r} (rbf, rbf-c, rbf-arm)")
    if not (0 < dt <= period and math.isfinite(period) and math.isfinite(duration) and duration > 0):
        raise HostError(f"need duration > 0 and 0 < dt <= period, got {duration!r}, {dt!r}, {period!r}")
    start = time.perf_counter()
    hist = simulate(controller, params, duration, period, dt)
    metrics = rbf_tracking.metrics_of(hist)
    metrics.update({"controller": controller, "theorem": params.theorem, "period": period, "dt": dt,
                    "wall_time_s": round(time.perf_counter() - start, 2), "paper": PAPER,
                    "parameters": params.to_mapping()})
    reference = None
    if CONTROLLERS[controller] is not None:
        reference = rbf_tracking.simulate(params, duration, period=period, dt=dt)
        ref_metrics = rbf_tracking.metrics_of(reference)
        metrics.update({"mode": TARGET_NAMES[CONTROLLERS[controller]],
                        "golden_mismatch_steps": int(hist["golden_mismatch_steps"]),
                        "float64": {k: ref_metrics[k] for k in ("t_rho_5m", "t_rho_1m", "t_attitude_1deg",
                                                                 "delta_v", "torque_impulse", "min_rho")},
                        **_diff_to(reference, hist)})
        if "cycles" in hist:
            cyc = hist["cycles"]
            metrics.update({"cycles_min": int(cyc.min()), "cycles_median": int(np.median(cyc)),
                            "cycles_max": int(cyc.max())})
    if out_dir is not None:
        write_outputs(Path(out_dir), metrics, hist, reference)
    return {"metrics": metrics, "history": hist, "reference": reference}


# ----------------------------------------------------------------------------- outputs


def write_outputs(out: Path, metrics: dict, hist: dict, reference: dict | None) -> None:
    atomic.write_json(out / "metrics.json", metrics)
    atomic.write_npz(out / "history.npz", {k: hist[k] for k in HISTORY_KEYS})
    _figure(out / "fig_range_los.png", lambda axes: _range_los(axes, hist, metrics), 2)
    _figure(out / "fig_attitude.png", lambda axes: _attitude(axes, hist, metrics), 2)
    _figure(out / "fig_rbf_estimate.png", lambda axes: _estimate(axes, hist), 3)
    _figure(out / "fig_commands.png", lambda axes: _commands(axes, hist), 2)
    if reference is not None:
        _figure(out / "fig_c_vs_float64.png", lambda axes: _c_vs_float64(axes, hist, reference, metrics), 1)


def format_seconds(x) -> str:
    """A band time of the metrics: None (the band is not held at the end) reads 'not reached'."""
    return "not reached" if x is None else f"{x:.1f} s"


def _title(metrics: dict) -> str:
    return f"{metrics['controller']}, theorem {metrics['theorem']}, T = {metrics['period']:g} s"


def _range_los(axes, hist, metrics) -> None:
    t = hist["t"]
    axes[0].plot(t, hist["los"][:, 0], label="ρ")
    axes[0].axhline(100.0, color="k", lw=0.8, ls="--", label="ρ_d = 100 m")
    axes[0].axvline(PAPER["t_approach_s"], color="r", lw=0.8, ls=":", label="paper: 22.9 s")
    axes[0].set_ylabel("range (m)")
    axes[0].set_title(f"Range and line-of-sight errors ({_title(metrics)})")
    axes[0].legend(loc="upper right", fontsize=8)
    for i, name in ((1, "q_ε − q_εd"), (2, "q_β − q_βd")):
        axes[1].plot(t, hist["e1"][:, i] / DEG, label=name)
    axes[1].set_ylabel("LOS error (deg)")
    axes[1].legend(loc="upper right", fontsize=8)


def _attitude(axes, hist, metrics) -> None:
    t = hist["t"]
    for i, name in enumerate(("φ", "θ", "ψ")):
        axes[0].plot(t, hist["e1"][:, 3 + i] / DEG, label=f"{name} − {name}_f")
        axes[1].semilogy(t, np.maximum(np.abs(hist["e1"][:, 3 + i]) / DEG, 1e-9), label=name)
    axes[0].axvline(PAPER["t_attitude_s"], color="r", lw=0.8, ls=":", label="paper: 5.7 s")
    axes[0].set_ylabel("attitude error (deg)")
    axes[0].set_title(f"Attitude errors ({_title(metrics)})")
    axes[0].legend(loc="upper right", fontsize=8)
    axes[1].set_ylabel("|error| (deg, log)")


def _estimate(axes, hist) -> None:
    """The paper's Fig. 4: the first network's estimate against the true unknown term (orbit channels)."""
    t = hist["t"][:-1]
    for ax, i, name, unit in ((axes[0], 0, "ρ", "m/s²"), (axes[1], 1, "q_ε", "rad/s²"), (axes[2], 2, "q_β", "rad/s²")):
        ax.plot(t, hist["w_true"][:-1, i], label="w (truth)", lw=0.8)
        ax.plot(t, hist["w_hat"][:-1, i], label="ŵ = θ̂ᵀφ", lw=0.8)
        ax.set_ylabel(f"{name} ({unit})")
        ax.legend(loc="upper right", fontsize=8)
    axes[0].set_title("RBF estimate against the true unknown term (paper's Fig. 4)")


def _commands(axes, hist) -> None:
    t = hist["t"][:-1]
    for i in range(3):
        axes[0].plot(t, hist["force_applied"][:-1, i], lw=0.6, label=f"F_{'xyz'[i]}")
        axes[1].plot(t, hist["torque_applied"][:-1, i], lw=0.6, label=f"T_{'xyz'[i]}")
    axes[0].set_ylabel("applied force (N, body)")
    axes[0].set_title("Applied thrust and torque (after dead zone and saturation)")
    axes[1].set_ylabel("applied torque (N·m)")
    for ax in axes:
        ax.legend(loc="upper right", fontsize=8)


def _c_vs_float64(axes, hist, reference, metrics) -> None:
    t = hist["t"]
    axes[0].semilogy(t, np.maximum(np.abs(hist["los"][:, 0] - reference["los"][:, 0]), 1e-12), label="|Δρ| (m)")
    axes[0].semilogy(t, np.maximum(np.max(np.abs(hist["e1"][:, 3:] - reference["e1"][:, 3:]), axis=1) / DEG, 1e-12),
                     label="max |Δ attitude error| (deg)")
    axes[0].set_title(f"{metrics['mode']} against the float64 law, same scenario")
    axes[0].legend(loc="lower right", fontsize=8)
