"""Paper 004's attitude takeover flown by the baseline and the GP law (docs/gp-takeover.md §1, §5, §12),
with the metrics behind the paper's qualitative claims and its Figs. 4-7.

`run(controller, params, duration, start, out_dir)`: controller "gp-baseline" (the baseline PD of the
law's file, float64) or "gp" (the GP law of the file: its trained artifact through reference_predict,
float64) on the takeover plant (host.sim.takeover.simulate: RK4 0.01 s, ZOH 0.1 s, perfect sensors).
`start`: "capture" (section 1's post-capture state) or "outside" (the paper's Fig. 7: 60° about the
capture axis, outside the 25° ball of the training data, same residual rates, wheels at rest; the
target still pulls towards its capture pointing).

The generated unit `gp` in the loop: "gp-c" (SIL, the x86 build through cffi) and "gp-arm" (PIL, the
ARM ELF in the emulator, cycles of every step), through tools.inloop.InTheLoop with the golden twin
stepping alongside (every output word compared); `record_controller(step)` adapts a step on the unit's
records to the closed-loop interface. Their metrics add the float64 run of the same file ("gp") and
the largest differences from it.
"""
from __future__ import annotations

import math
import time
from pathlib import Path
from typing import Callable

import numpy as np

from codegen import atomic
from codegen.units.gp.params import GpLawParams
from codegen.units.gp.records import INPUT_DTYPE
from host.control.takeover_laws import LawOutput, baseline_law, gp_law, variance_fraction
from host.core.constants import DEG
from host.errors import HostError
from host.plant.spacecraft import pack_state
from host.plant.takeover import CAPTURE_AXIS, CAPTURE_RATE, TakeoverPlant, axis_angle_quat, capture_state
from host.sim.plots import stacked_figure as _figure
from host.sim.scenarios import configure_unit
from host.sim.takeover import Controller, law_controller, metrics_of, simulate
from tools.inloop import InTheLoop

CONTROLLERS = ("gp-baseline", "gp", "gp-c", "gp-arm")
TARGETS = {"gp-c": "x86", "gp-arm": "arm"}
TARGET_NAMES = {"x86": "SIL x86", "arm": "PIL ARM emulator"}
STARTS = ("capture", "outside")
DEFAULT_DURATION = 600.0       # s
OUTSIDE_ANGLE = 60.0 * DEG     # rad, about the capture axis (training data: setpoints within 25°)
WINDOW = 60.0                  # s, the first / last window of the variance and gain means
PAPER = {"figs_4_6": "the GP law settles faster and to a smaller set than the baseline (L35)",
         "fig_7": "after a large manoeuvre the variance and the gains rise outside the training region, "
                  "then fall as the state returns to it (L36)"}
HISTORY_KEYS = ("t", "q", "omega", "h_w", "angle", "torque", "torque_applied", "counter_torque", "mu", "var",
                "gains", "d_true", "d0", "var_fraction")
AXES = ("x", "y", "z")


# ----------------------------------------------------------------------------- controllers


RecordStep = Callable[[np.ndarray], np.ndarray]


def record_controller(step: RecordStep) -> Controller:
    """A unit step on the gp unit's records (one INPUT_DTYPE record in, one output record out) as a
    closed-loop controller (float32 in, float64 out)."""
    def controller(t, q, omega, h_w) -> LawOutput:
        rec = np.zeros(1, dtype=INPUT_DTYPE)
        rec["q"], rec["omega"], rec["h_w"] = q, omega, h_w
        out = np.asarray(step(rec)).reshape(-1)[0]
        return LawOutput(*(np.asarray(out[k], dtype=float).reshape(n) for k, n in
                           (("torque", 3), ("mu", 3), ("var", 3), ("gains", 2))))
    return controller


def unit_loop(name: str, params: GpLawParams) -> InTheLoop:
    """The generated unit on the target of gp-c / gp-arm, its golden twin alongside."""
    return InTheLoop(configure_unit("gp", params=params), TARGETS[name])


def controller_for(name: str, params: GpLawParams, loop: InTheLoop | None = None) -> Controller:
    """The closed-loop controller of a name (gp-c / gp-arm fly `loop`, made by unit_loop if not given)."""
    if name == "gp-baseline":
        return law_controller(baseline_law(params))
    if name == "gp":
        return law_controller(gp_law(params))
    if name in TARGETS:
        return record_controller((loop or unit_loop(name, params)).step)
    raise HostError(f"unknown controller {name!r} ({', '.join(CONTROLLERS)})")


def start_state(plant: TakeoverPlant, start: str) -> np.ndarray:
    if start == "capture":
        return capture_state(plant)
    if start == "outside":
        return pack_state(axis_angle_quat(CAPTURE_AXIS, OUTSIDE_ANGLE), CAPTURE_RATE, np.zeros(3))
    raise HostError(f"unknown start {start!r} ({', '.join(STARTS)})")


def prior_variance(params: GpLawParams) -> np.ndarray:
    """s_y,k² σ_f² per axis (the gp law's normalisation of the variance)."""
    a = params.gp.arrays
    return np.asarray(a.output_scale, float) ** 2 * float(a.outputscale)


# ----------------------------------------------------------------------------- closed loop


def fly(controller: Controller, params: GpLawParams, duration: float, start: str,
        plant: TakeoverPlant | None = None) -> dict:
    """History of one closed loop of any controller object, with the oracle d₀ (d at ω̇ = 0, what the
    GP mean should equal) and the variance fraction s the law schedules on."""
    plant = plant or TakeoverPlant()
    hist = simulate(controller, duration, plant, start_state(plant, start))
    hist["d0"] = np.array([plant.unknown_term_at_rest_acceleration(q, w) for q, w in zip(hist["q"], hist["omega"])])
    pv = prior_variance(params)
    n = len(hist["t"]) - 1
    hist["var_fraction"] = np.concatenate([[variance_fraction(v, pv) for v in hist["var"][:n]], [np.nan]])
    return hist


def _window_means(t, values, first: bool, window: float = WINDOW):
    """Mean over the first / last `window` s of the control instants (the last row has no command)."""
    tc, vc = t[:-1], values[:-1]
    sel = tc < tc[0] + window if first else tc >= tc[-1] - window
    return np.mean(vc[sel], axis=0)


def gp_metrics(hist: dict, controller: str) -> dict:
    """The GP's side: variance fraction and gains over the first and last minute, the mean's error
    against the oracle d₀ (RMS per axis)."""
    t = hist["t"]
    out = {"gains_first_60s": _window_means(t, hist["gains"], True).tolist(),
           "gains_last_60s": _window_means(t, hist["gains"], False).tolist()}
    if controller == "gp-baseline":
        return {**out, "var_fraction_first_60s": None, "var_fraction_last_60s": None, "mu_rms_error": None}
    err = hist["mu"][:-1] - hist["d0"][:-1]
    return {**out, "var_fraction_first_60s": float(_window_means(t, hist["var_fraction"], True)),
            "var_fraction_last_60s": float(_window_means(t, hist["var_fraction"], False)),
            "var_fraction_max": float(np.nanmax(hist["var_fraction"])),
            "mu_rms_error": np.sqrt(np.mean(err ** 2, axis=0)).tolist(),
            "d0_rms": np.sqrt(np.mean(hist["d0"][:-1] ** 2, axis=0)).tolist()}


def run(controller: str, params: GpLawParams, duration: float = DEFAULT_DURATION, start: str = "capture",
        out_dir: Path | None = None, record: dict | None = None) -> dict:
    """Metrics (and, with out_dir, metrics.json, history.npz and the figures) of one controller; `record`
    (e.g. the law file's path) is added to the metrics."""
    if not (isinstance(duration, (int, float)) and math.isfinite(duration) and duration > 0):
        raise HostError(f"duration must be a positive number of seconds, got {duration!r}")
    if controller not in CONTROLLERS:
        raise HostError(f"unknown controller {controller!r} ({', '.join(CONTROLLERS)})")
    if start not in STARTS:
        raise HostError(f"unknown start {start!r} ({', '.join(STARTS)})")
    loop = unit_loop(controller, params) if controller in TARGETS else None
    clock = time.perf_counter()
    hist = fly(controller_for(controller, params, loop), params, duration, start)
    metrics = {"controller": controller, "start": start, **metrics_of(hist), **gp_metrics(hist, controller)}
    metrics["max_abs_torque"] = float(np.max(np.abs(hist["torque_applied"][:-1])))
    metrics.update({"wall_time_s": round(time.perf_counter() - clock, 2), "period": float(hist["period"]),
                    "n_inducing": params.n_inducing, "prior_variance": prior_variance(params).tolist(),
                    "artifact_sha256": params.gp.sha256,
                    "law_sha256": params.sha256(), "law": params.law_mapping(), "paper": PAPER, **(record or {})})
    if loop is not None:
        metrics.update(in_the_loop_metrics(loop, hist, fly(controller_for("gp", params), params, duration, start)))
    if out_dir is not None:
        write_outputs(Path(out_dir), metrics, hist)
    return {"metrics": metrics, "history": hist}


def in_the_loop_metrics(loop: InTheLoop, hist: dict, reference: dict) -> dict:
    """The C run against its golden twin (mismatching steps) and against the float64 law (largest
    differences of the error angle, torque, mean and variance over the run; the float64 metrics)."""
    n = len(hist["t"]) - 1
    ref_metrics = metrics_of(reference)
    out = {"mode": TARGET_NAMES[loop.target],
           "golden_mismatch_steps": int(loop.mismatch_steps),
           "max_angle_diff_deg": float(np.max(np.abs(hist["angle"] - reference["angle"])) / DEG),
           "max_torque_diff": float(np.max(np.abs(hist["torque"][:n] - reference["torque"][:n]))),
           "max_mu_diff": float(np.max(np.abs(hist["mu"][:n] - reference["mu"][:n]))),
           "max_var_fraction_diff": float(np.nanmax(np.abs(hist["var_fraction"][:n] - reference["var_fraction"][:n]))),
           "float64": {k: ref_metrics[k] for k in ref_metrics if k.startswith(("t_", "steady"))}}
    cycles = loop.cycles
    if cycles:
        out.update({"cycles_min": int(min(cycles)), "cycles_median": int(np.median(cycles)),
                    "cycles_max": int(max(cycles))})
    return out


# ----------------------------------------------------------------------------- outputs


def write_outputs(out: Path, metrics: dict, hist: dict) -> None:
    atomic.write_json(out / "metrics.json", metrics)
    atomic.write_npz(out / "history.npz", {k: hist[k] for k in HISTORY_KEYS})
    _figure(out / "fig4_attitude.png", lambda axes: _attitude(axes, hist, metrics), 2)
    _figure(out / "fig5_rates.png", lambda axes: _rates(axes, hist, metrics), 1)
    _figure(out / "fig6_torque.png", lambda axes: _torque(axes, hist, metrics), 2)
    if metrics["controller"] != "gp-baseline":
        _figure(out / "fig7_variance_gains.png", lambda axes: _variance_gains(axes, hist, metrics), 3)
        _figure(out / "fig_gp_mean.png", lambda axes: _gp_mean(axes, hist, metrics), 3)


def _title(metrics: dict) -> str:
    return f"{metrics['controller']}, start {metrics['start']}, M = {metrics['n_inducing']}"


def _attitude(axes, hist, metrics) -> None:
    """Fig. 4: the error angle (log) and q_v."""
    t = hist["t"]
    axes[0].semilogy(t, np.maximum(hist["angle"] / DEG, 1e-6), lw=0.9, label="error angle")
    for band in (1.0, 0.1):
        axes[0].axhline(band, color="k", lw=0.6, ls="--")
    axes[0].set_ylabel("error angle (deg)")
    axes[0].set_title(f"Attitude (paper's Fig. 4; {_title(metrics)})")
    q_v = hist["q"][:, :3] * np.sign(hist["q"][:, 3:4] + (hist["q"][:, 3:4] == 0))
    for i in range(3):
        axes[1].plot(t, q_v[:, i], lw=0.8, label=f"q_{i + 1}")
    axes[1].set_ylabel("q_v")
    axes[1].legend(loc="upper right", fontsize=8)


def _rates(axes, hist, metrics) -> None:
    """Fig. 5: body rates."""
    for i in range(3):
        axes[0].plot(hist["t"], hist["omega"][:, i] / DEG, lw=0.8, label=f"ω_{AXES[i]}")
    axes[0].set_ylabel("ω (deg/s)")
    axes[0].set_title(f"Angular velocity (paper's Fig. 5; {_title(metrics)})")
    axes[0].legend(loc="upper right", fontsize=8)


def _torque(axes, hist, metrics) -> None:
    """Fig. 6: applied wheel torque, and the wheel momentum against the 50 N·m·s limit."""
    t = hist["t"]
    for i in range(3):
        axes[0].plot(t[:-1], hist["torque_applied"][:-1, i], lw=0.6, label=f"u_{AXES[i]}")
        axes[1].plot(t, hist["h_w"][:, i], lw=0.8, label=f"h_{AXES[i]}")
    axes[0].set_ylabel("torque (N·m)")
    axes[0].set_title(f"Control torque (paper's Fig. 6; {_title(metrics)})")
    axes[1].axhline(50.0, color="k", lw=0.6, ls="--")
    axes[1].axhline(-50.0, color="k", lw=0.6, ls="--")
    axes[1].set_ylabel("wheel momentum (N·m·s)")
    for ax in axes:
        ax.legend(loc="upper right", fontsize=8)


def _variance_gains(axes, hist, metrics) -> None:
    """Fig. 7: the normalised variance per axis and its max s, and the gains K1, K2."""
    t = hist["t"][:-1]
    ratio = hist["var"][:-1] / np.asarray(metrics["prior_variance"])
    for i in range(3):
        axes[0].plot(t, ratio[:, i], lw=0.7, label=f"σ²_{AXES[i]} / σ²_prior")
    axes[0].plot(t, hist["var_fraction"][:-1], "k", lw=1.0, label="s (max, clamped)")
    axes[0].set_ylabel("normalised variance")
    axes[0].set_title(f"Variance and gains (paper's Fig. 7; {_title(metrics)})")
    axes[0].legend(loc="upper right", fontsize=8)
    axes[1].plot(t, hist["gains"][:-1, 0], lw=0.9)
    axes[1].set_ylabel("K1 (N·m)")
    axes[2].plot(t, hist["gains"][:-1, 1], lw=0.9)
    axes[2].set_ylabel("K2 (N·m·s/rad)")


def _gp_mean(axes, hist, metrics) -> None:
    """The GP mean μ against the true unknown term at ω̇ = 0 (d₀) and at the actual ω̇ (d)."""
    t = hist["t"][:-1]
    for i, ax in enumerate(axes):
        ax.plot(t, hist["d_true"][:-1, i], color="0.7", lw=0.6, label="d (truth, actual ω̇)")
        ax.plot(t, hist["d0"][:-1, i], "k", lw=0.9, label="d₀ (truth, ω̇ = 0)")
        ax.plot(t, hist["mu"][:-1, i], "C1", lw=0.9, label="GP mean μ")
        ax.set_ylabel(f"d_{AXES[i]} (N·m)")
    axes[0].set_title(f"GP mean against the true unknown term ({_title(metrics)})")
    axes[0].legend(loc="upper right", fontsize=8)


__all__ = ["CONTROLLERS", "STARTS", "run", "fly", "controller_for", "record_controller", "start_state",
           "gp_metrics", "write_outputs", "DEFAULT_DURATION"]
