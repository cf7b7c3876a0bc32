"""Figures and files of `staregen evaluate` in the paper's numbering: Fig. 10 (J_A vs J_ω per target, every
controller), Figs. 11-12 (step responses on the first response target), Figs. 13-14 (magnitude of
the attitude response to the 0.03 N·m periodic torque). PNG through host.sim.plots (atomic)."""
from __future__ import annotations

from pathlib import Path

import numpy as np

from codegen import atomic
from host.plant.error_model import TABLE6_ERRORS, ErrorModel
from host.sim import impulse, plots

AXES = ("x", "y", "z")


def fig10_scatter(staring: dict, path: Path) -> Path:
    plt = plots.plt
    fig, ax = plt.subplots(figsize=(6.5, 4.8))
    most = max(row["targets"] for row in staring.values())
    for label, row in staring.items():
        if row["targets"] == most:      # rows over every target (the PIL row flies the central one only)
            ax.scatter(row["per_target"]["J_A"], row["per_target"]["J_w"], s=10, label=label)
    ax.set_xlabel("J_A [°]")
    ax.set_ylabel("J_ω [°/s]")
    ax.set_title("Fig. 10: pointing accuracy vs stability, one point per target")
    ax.grid(True, lw=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    return plots.save_figure(fig, path)


def fig11_12_step(step: dict, path: Path) -> Path:
    plt = plots.plt
    fig, axes = plt.subplots(len(step), 1, figsize=(7.5, 2.6 * len(step)), sharex=True, squeeze=False)
    for ax, (label, s) in zip(axes[:, 0], step.items()):
        d = np.asarray(s["first_target_response_deg"])
        for a in range(3):
            ax.plot(s["t"], d[:, a], lw=0.9, label=f"{AXES[a]}")
        ax.axhline(-0.005, color="k", lw=0.7, ls="--")
        ax.axhspan(-0.005 * 1.05, -0.005 * 0.95, color="0.85")
        ax.set_ylabel("ΔA_bd [°]")
        ax.set_title(f"{label}: response to a 0.005° measurement step at 30 s", fontsize=9)
        ax.grid(True, lw=0.3)
        ax.legend(fontsize=8, ncol=3)
    axes[-1, 0].set_xlabel("t [s]")
    fig.tight_layout()
    return plots.save_figure(fig, path)


def fig13_14_frequency(freq: dict, path: Path) -> Path:
    plt = plots.plt
    fig, axes = plt.subplots(1, 3, figsize=(11, 3.8), sharey=True)
    for label, f in freq.items():
        amp = np.asarray(f["amplitude_deg"])
        for a, ax in enumerate(axes):
            ax.loglog(f["freqs_hz"], amp[a], marker="o", ms=3, lw=0.9, label=label)
    for a, ax in enumerate(axes):
        ax.set_title(f"{AXES[a]} axis: 0.03 N·m sine on {AXES[a]}", fontsize=9)
        ax.set_xlabel("frequency [Hz]")
        ax.grid(True, lw=0.3, which="both")
    axes[0].set_ylabel("amplitude of A_bd [°]")
    axes[0].legend(fontsize=8)
    fig.tight_layout()
    return plots.save_figure(fig, path)


def write_evaluation(result: dict, network: str, seed: int, out: Path, errors: ErrorModel = TABLE6_ERRORS) -> dict:
    """Add the impulse response of the network (Fig. 15) to `result`, then write evaluate.json and
    Figs. 10-15 into `out` (created). Returns `result`."""
    imp = impulse.run("nn", network, seed=seed, errors=errors)
    result["impulse"] = imp.as_dict()
    out.mkdir(parents=True, exist_ok=True)
    fig10_scatter(result["staring"], out / "fig10_scatter.png")
    fig11_12_step(result["step"], out / "fig11_12_step.png")
    fig13_14_frequency(result["frequency"], out / "fig13_14_frequency.png")
    impulse.plot(imp, out / "fig15_impulse.png", "NN (float64)")
    atomic.write_json(out / "evaluate.json", result)
    return result
