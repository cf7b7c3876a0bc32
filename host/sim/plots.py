"""Error plots like paper 001 Figs. 6-7 (Euler-angle error, angular-velocity error) and Fig. 10
(J_A vs J_ω per target). Matplotlib Agg backend, PNG, written atomically."""
from __future__ import annotations

from pathlib import Path
from typing import Sequence

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

from host.core.constants import DEG  # noqa: E402
from codegen import atomic  # noqa: E402

_AXES = ("x", "y", "z")


def save_figure(fig, path: Path) -> Path:
    with atomic.writing(path, suffix=".png") as tmp:
        fig.savefig(tmp, dpi=110, format="png")
    plt.close(fig)
    return Path(path)


def stacked_figure(path: Path, draw, rows: int) -> Path:
    """`rows` time plots stacked on one shared t axis, drawn by draw(axes), gridded and saved."""
    fig, axes = plt.subplots(rows, 1, figsize=(8, 2.6 * rows + 0.8), sharex=True, squeeze=False)
    draw(axes[:, 0])
    for ax in axes[:, 0]:
        ax.grid(True, alpha=0.3)
    axes[-1, 0].set_xlabel("t (s)")
    fig.tight_layout()
    return save_figure(fig, path)


def _three_axis_plot(t, values, labels, ylabel, title, path) -> Path:
    fig, axes = plt.subplots(3, 1, figsize=(7.5, 6.5), sharex=True)
    for i, ax in enumerate(axes):
        ax.plot(t, values[:, i], lw=0.8)
        ax.set_ylabel(labels[i])
        ax.grid(True, lw=0.3)
    axes[0].set_title(title)
    axes[-1].set_xlabel("t [s]")
    fig.supylabel(ylabel)
    fig.tight_layout()
    return save_figure(fig, path)


def plot_euler_error(t, A_e_rad, path, title: str = "Euler angle error") -> Path:
    """Fig. 6 style: φ_e, θ_e, ψ_e in degrees."""
    return _three_axis_plot(t, A_e_rad / DEG, ("φ_e [°]", "θ_e [°]", "ψ_e [°]"),
                            "Euler angle error (3-1-2, body w.r.t. desired)", title, path)


def plot_rate_error(t, w_e_rad_s, path, title: str = "Angular velocity error") -> Path:
    """Fig. 7 style: ω_e components in degrees per second."""
    return _three_axis_plot(t, w_e_rad_s / DEG, tuple(f"ω_e{a} [°/s]" for a in _AXES),
                            "angular velocity error ω_b − ω_d", title, path)


def plot_target_scatter(J_A: Sequence[float], J_w: Sequence[float], path, label: str = "PID") -> Path:
    """Fig. 10 style: pointing accuracy vs pointing stability, one point per target."""
    fig, ax = plt.subplots(figsize=(6, 4.5))
    ax.scatter(J_A, J_w, s=10, label=label)
    ax.set_xlabel("J_A [°]")
    ax.set_ylabel("J_ω [°/s]")
    ax.grid(True, lw=0.3)
    ax.legend()
    fig.tight_layout()
    return save_figure(fig, path)
