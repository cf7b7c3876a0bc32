"""Impulse response (paper 001 Sec. 7.8, Fig. 15): 1 N·m on each body axis from 30 s for 0.5 s
while staring at the central target. The disturbance drives the errors far outside Table 2, the
PID fallback takes over, converges and hands back to the network.

Reported: when the PID first commanded (must be at the first control instant after 30 s), when
the network was back for good, the peak errors, and the Fig. 15 plot (Euler angle errors, log
scale, and the mode) written next to the metrics.
"""
from __future__ import annotations

from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from host.core.constants import DEG
from host.control.controllers import ARTIFACT_CONTROLLERS, build_controller
from host.plant.error_model import TABLE6_ERRORS, ErrorModel
from host.sim.simulator import History, SimConfig, simulate
from host.sim.targets import central_target
from codegen import atomic

IMPULSE_START = 30.0     # s
IMPULSE_LENGTH = 0.5     # s
IMPULSE_TORQUE = 1.0     # N·m on each axis
DEFAULT_DURATION = 60.0  # s


def impulse_torque(t: float) -> np.ndarray:
    on = IMPULSE_START <= t < IMPULSE_START + IMPULSE_LENGTH - 1e-9
    return np.full(3, IMPULSE_TORQUE if on else 0.0)


@dataclass(frozen=True)
class ImpulseResult:
    history: History
    t_pid_first: float | None    # s, first control instant flown by the PID at or after the impulse
    t_nn_back: float | None      # s, start of the final stretch flown by the network
    peak_A_deg: float            # max |A_bd| after the impulse
    peak_w_deg_s: float          # max |ω_e| after the impulse
    final_A_deg: float           # max |A_bd| over the last 5 s

    def as_dict(self) -> dict:
        return {"t_pid_first_s": self.t_pid_first, "t_nn_back_s": self.t_nn_back,
                "nn_back_after_impulse_end_s": (None if self.t_nn_back is None
                                                else self.t_nn_back - IMPULSE_START - IMPULSE_LENGTH),
                "peak_A_bd_deg": self.peak_A_deg, "peak_omega_e_deg_s": self.peak_w_deg_s,
                "final_max_A_bd_deg": self.final_A_deg,
                "impulse": {"start_s": IMPULSE_START, "length_s": IMPULSE_LENGTH, "torque_Nm": IMPULSE_TORQUE}}


def mode_times(t: np.ndarray, mode: np.ndarray) -> tuple[float | None, float | None]:
    """(first PID instant at or after the impulse, start of the last all-network stretch)."""
    pid = mode == "pid"
    after = t >= IMPULSE_START - 1e-9
    first = t[after & pid]
    t_pid = float(first[0]) if first.size else None
    if pid[-1]:
        return t_pid, None
    last_pid = np.flatnonzero(pid)
    t_back = float(t[last_pid[-1] + 1]) if last_pid.size else float(t[0])
    return t_pid, t_back


def run(controller: str = "nn", artifact: str | None = None, duration: float = DEFAULT_DURATION,
        seed: int = 0, errors: ErrorModel = TABLE6_ERRORS) -> ImpulseResult:
    opts = {"artifact": artifact} if controller in ARTIFACT_CONTROLLERS else {}
    c = build_controller(controller, torque_limit=1.0, control_period=0.1, **opts)
    tg = central_target()
    cfg = replace(SimConfig(duration=duration, seed=seed, errors=errors), extra_torque=impulse_torque)
    h = simulate(c, tg.lon, tg.lat, cfg)
    t_pid, t_back = mode_times(h.t, h.mode)
    after = h.t >= IMPULSE_START
    last = h.t >= h.t[-1] - 5.0
    return ImpulseResult(h, t_pid, t_back, float(np.max(np.abs(h.A_bd[after])) / DEG),
                         float(np.max(np.abs(h.omega_e[after])) / DEG), float(np.max(np.abs(h.A_bd[last])) / DEG))


def plot(r: ImpulseResult, path: Path, label: str) -> Path:
    """Fig. 15 style: |Euler angle errors| and |rate errors| (log scale) with their Table 2 bounds,
    and the mode."""
    from host.sim import plots

    plt = plots.plt
    h = r.history
    fig, (ax, axw, axm) = plt.subplots(3, 1, figsize=(7.5, 8.0), sharex=True,
                                       gridspec_kw={"height_ratios": [3, 3, 1]})
    for a, values, bound, unit, names in ((ax, h.A_bd, 0.02, "°", ("φ_e", "θ_e", "ψ_e")),
                                           (axw, h.omega_e, 0.004, "°/s", ("ω_ex", "ω_ey", "ω_ez"))):
        for i, name in enumerate(names):
            a.semilogy(h.t, np.abs(values[:, i]) / DEG + 1e-9, lw=0.8, label=name)
        a.axhline(bound, color="k", lw=0.8, ls="--", label=f"Table 2 bound {bound:g}{unit}")
        a.axvspan(IMPULSE_START, IMPULSE_START + IMPULSE_LENGTH, color="r", alpha=0.2, label="1 N·m impulse")
        a.set_ylabel(f"|error| [{unit}]")
        a.legend(fontsize=8, ncol=3)
        a.grid(True, lw=0.3, which="both")
    ax.set_title(f"Impulse response, {label}, central target")
    axm.step(h.t, (h.mode == "pid").astype(float), where="post", lw=0.9)
    axm.set_yticks([0, 1], ["NN", "PID"])
    axm.set_xlabel("t [s]")
    axm.grid(True, lw=0.3)
    fig.tight_layout()
    return plots.save_figure(fig, path)


def write(r: ImpulseResult, out: Path, controller: str, scenario: dict | None = None) -> None:
    """scenario: the scenario file's description (recorded)."""
    out = Path(out)
    atomic.write_json(out / "impulse.json", {"controller": controller, "scenario": scenario, **r.as_dict()})
    plot(r, out / "impulse.png", controller)
