"""A staring campaign: one controller over a list of targets -> histories, metrics, artifacts.

Shared by `staregen simulate` and `staregen pipeline`. Output folder layout (written by
write_campaign into a folder the caller builds atomically):

    metrics.json        top-level J_A [deg], J_w [deg/s], J (averages over targets, eq. 25-27, when
                        several) + settings + a per-target list
    history.npz         one target: every History array at the plant step
    histories.npz       several targets: key arrays at the control instants, stacked (target, time, 3)
    euler_error.png, rate_error.png   Figs. 6-7 style, for the first target
    targets_JA_Jw.png   several targets: Fig. 10 style scatter
"""
from __future__ import annotations

import functools
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Sequence

import numpy as np

from host.sim import plots
from host.core.constants import DEG
from host.control.controllers import build_controller
from host.plant.earth import elevation
from host.errors import HostError
from host.sim.metrics import DEFAULT_PLAN, ImagingPlan, StaringMetrics, average_metrics, staring_metrics
from host.sim.simulator import History, SimConfig, environment_track, simulate_targets
from host.sim.targets import Target
from codegen import atomic


@dataclass
class CampaignResult:
    controller: str
    targets: list[Target]
    config: SimConfig
    plan: ImagingPlan
    histories: list[History]
    metrics: list[StaringMetrics]
    average: StaringMetrics
    run_time_s: float


def check_targets_visible(targets: Sequence[Target], config: SimConfig) -> None:
    """A target below the horizon at any time of the run cannot be stared at: a user error."""
    env = environment_track(config.control_steps * config.substeps + 1, config.plant_step)
    for tg in targets:
        el = elevation(env.R, env.jd_days, env.sec_of_day, tg.lon, tg.lat, tg.height)
        if np.min(el) <= 0.0:
            raise HostError(f"target {tg.name} ({tg.lon_deg:g}°, {tg.lat_deg:g}°) is below the horizon "
                            f"during the run (min elevation {np.min(el) / DEG:.1f}°); it cannot be stared at")


def validate_campaign(controller: str, targets: Sequence[Target], config: SimConfig,
                      plan: ImagingPlan, options: dict | None = None) -> functools.partial:
    """Every user error (bad controller, no imaging window, target below the horizon) raised
    before anything runs or is written; returns the picklable controller factory."""
    plan.windows(config.control_steps * config.control_period)
    make = functools.partial(build_controller, controller, torque_limit=config.spacecraft.torque_limit,
                             control_period=config.control_period, **(options or {}))
    make()
    check_targets_visible(targets, config)
    return make


def run_campaign(controller: str, targets: Sequence[Target], config: SimConfig = SimConfig(),
                 plan: ImagingPlan = DEFAULT_PLAN, workers: int | None = None,
                 progress: bool = True, options: dict | None = None) -> CampaignResult:
    """options: keyword arguments of the controller factory (e.g. artifact=PATH)."""
    make = validate_campaign(controller, targets, config, plan, options)
    start = time.perf_counter()
    histories = simulate_targets(make, [(tg.lon, tg.lat) for tg in targets], config,
                                 workers=workers, progress=progress and len(targets) > 1)
    run_time = time.perf_counter() - start
    metrics = [staring_metrics(h.t, h.A_bd, h.omega_e, plan,
                               t_end=config.control_steps * config.control_period) for h in histories]
    return CampaignResult(controller, list(targets), config, plan, histories, metrics,
                          average_metrics(metrics), run_time)


# ----------------------------------------------------------------------------- reporting

def _target_row(tg: Target, h: History, m: StaringMetrics, plan: ImagingPlan) -> dict:
    settled = h.t >= plan.t_first
    return {
        "name": tg.name, "lon_deg": tg.lon_deg, "lat_deg": tg.lat_deg,
        "J_A": m.J_A, "J_w": m.J_w, "J": m.J,
        "max_abs_A_bd_deg_after_settling": float(np.max(np.abs(h.A_bd[settled])) / DEG),
        "max_abs_torque_cmd_Nm": float(np.max(np.abs(h.torque_cmd))),
        "max_abs_wheel_momentum_Nms": float(np.max(np.abs(h.h_w))),
    }


def metrics_document(r: CampaignResult, scenario: dict | None = None) -> dict:
    cfg = r.config
    return {
        "scenario": scenario or {"reading": cfg.errors.reading},
        "controller": r.controller,
        "J_A": r.average.J_A, "J_w": r.average.J_w, "J": r.average.J,
        "n_targets": len(r.targets),
        "units": {"J_A": "deg", "J_w": "deg/s", "J": "J_A + 5 s * J_w (k1 = 1, k2 = 5)"},
        "imaging": {"T_img_s": r.plan.T_img, "t_first_s": r.plan.t_first,
                    "images_per_target": r.metrics[0].m, "steps_per_window": r.metrics[0].p},
        "simulation": {"duration_s": cfg.control_steps * cfg.control_period,
                       "control_period_s": cfg.control_period, "plant_step_s": cfg.plant_step,
                       "seed": cfg.seed, "torque_limit_Nm": cfg.spacecraft.torque_limit,
                       "momentum_limit_Nms": cfg.spacecraft.momentum_limit,
                       "sensor_errors": cfg.sensor_errors, "wheel_errors": cfg.wheel_errors,
                       "external_torques": cfg.external_torques},
        "run_time_s": r.run_time_s,
        "targets": [_target_row(tg, h, m, r.plan) for tg, h, m in zip(r.targets, r.histories, r.metrics)],
    }


def format_table(r: CampaignResult) -> str:
    head = f"{'target':<10} {'lon[°]':>9} {'lat[°]':>8} {'J_A[°]':>10} {'J_w[°/s]':>10} {'J':>10} {'max|A_bd|[°]':>13} {'max|M|[Nm]':>11}"
    lines = [f"controller {r.controller}: {len(r.targets)} target(s), {r.config.control_steps * r.config.control_period:g} s, "
             f"T_img {r.plan.T_img:g} s from {r.plan.t_first:g} s, seed {r.config.seed}", head]
    for row in metrics_document(r)["targets"]:
        lines.append(f"{row['name']:<10} {row['lon_deg']:9.4f} {row['lat_deg']:8.4f} {row['J_A']:10.3e} "
                     f"{row['J_w']:10.3e} {row['J']:10.3e} {row['max_abs_A_bd_deg_after_settling']:13.3e} "
                     f"{row['max_abs_torque_cmd_Nm']:11.4f}")
    if len(r.targets) > 1:
        a = r.average
        lines.append(f"{'mean':<10} {'':>9} {'':>8} {a.J_A:10.3e} {a.J_w:10.3e} {a.J:10.3e}")
    lines.append(f"run time {r.run_time_s:.1f} s")
    return "\n".join(lines)


def _save_npz(path: Path, arrays: dict) -> None:
    atomic.write_npz(path, arrays)


def write_campaign(r: CampaignResult, out: Path, scenario: dict | None = None) -> None:
    """scenario: the scenario file's description (host.sim.scenario_file.Scenario.describe), recorded."""
    out = Path(out)
    atomic.write_json(out / "metrics.json", metrics_document(r, scenario))
    if len(r.histories) == 1:
        _save_npz(out / "history.npz", r.histories[0].arrays())
    else:
        k = r.config.substeps   # control instants only, to keep 100 targets to ~10 MB
        hs = r.histories
        _save_npz(out / "histories.npz", {
            "t": hs[0].t[::k], "names": np.array([tg.name for tg in r.targets]),
            "lon": np.array([tg.lon for tg in r.targets]), "lat": np.array([tg.lat for tg in r.targets]),
            **{f: np.stack([getattr(h, f)[::k] for h in hs]) for f in
               ("A_bd", "omega_e", "torque_cmd", "torque_applied", "h_w")}})
        plots.plot_target_scatter([m.J_A for m in r.metrics], [m.J_w for m in r.metrics],
                                  out / "targets_JA_Jw.png", label=r.controller)
    h, name = r.histories[0], r.targets[0].name
    plots.plot_euler_error(h.t, h.A_bd, out / "euler_error.png", f"Euler angle error, {r.controller}, {name}")
    plots.plot_rate_error(h.t, h.omega_e, out / "rate_error.png", f"Angular velocity error, {r.controller}, {name}")
