"""`staregen basilisk --package DIR --controller fig2|pid|tanh`: the flight package's C flown in Basilisk.

fig2 / pid: the staring scenario (Table 5 orbit, Table 6 body and wheels, disturbances, the
scenario file's sensor and wheel errors) flown by the package's `<name>_step`; the same metrics
file, histories and plots as `staregen simulate`. tanh: paper 000's example flown by
`<name>_tanh_step`. `--compare` flies the same package object code in staregen's simulator from
the same initial state with the same noise draws and writes the cross-check (crosscheck.json,
overlay plot). The disturbances (gravity gradient, drag, residual magnetic dipole; each switchable) are the same
model on both sides. The package is checked against its manifest before anything is compiled; one that
fails is never loaded. Needs the optional extra `basilisk` (pip install -e '.[basilisk]').
"""
from __future__ import annotations

import argparse
import dataclasses
import functools
import time
from pathlib import Path

import numpy as np

from codegen import atomic
from codegen import units as unit_registry
from codegen.package.manifest import load_key
from codegen.units.tanh.unit import TanhUnit
from host.cli.args import add_scenario_argument, load_scenario, parse_int, parse_number, shown
from host.cli.simulate import MAX_DURATION_S, build_plan
from host.cli.units import PAPER000_PARAMS
from host.control.package_controller import PackageTanhLaw, loaded_package, make_package_controller, pid_only
from host.errors import HostError
from host.outputs import check_output_folder, json_marker_owner
from host.plant.disturbances import DisturbanceParams
from host.sim import basilisk, crosscheck, tanh_example, tanh_in_loop
from host.sim.campaign import CampaignResult, check_targets_visible, format_table, write_campaign
from host.sim.metrics import average_metrics, staring_metrics
from host.sim.simulator import SimConfig, simulate, simulate_targets
from host.sim.targets import parse_target

CONTROLLERS = ("fig2", "pid", "tanh")
DEFAULT_DURATION_S = 100.0
TANH_DEFAULT_DURATION_S = 40.0
TANH_DEFAULT_DT = tanh_example.MAX_REFERENCE_STEP
TANH_SETTLE_TOLERANCE = 0.05      # issue 28: the same convergence time within ±5 %
OWNED = json_marker_owner("metrics.json")
# The disturbances both simulators model here (docs/basilisk.md); staregen's solar-radiation torque needs
# the Sun's ephemeris, which Basilisk fetches at run time (SPICE), and is off on both sides.
DISTURBANCES = ("gravity-gradient", "drag", "magnetic")


def register(subparsers) -> None:
    p = subparsers.add_parser("basilisk", help="fly a flight package's C in Basilisk (optional extra) and "
                              "cross-check it against staregen's simulator", description=__doc__.splitlines()[0])
    p.add_argument("--package", required=True, metavar="DIR", help="flight package folder (staregen generate)")
    p.add_argument("--controller", default="fig2",
                   help="fig2 (the package's controller: network + PID fallback), pid (the controller of a package "
                        "generated with --pid-only), tanh (the package's tanh unit on paper 000's example); default fig2")
    p.add_argument("--target", default="central", help="'central', 'all' (the 100 targets) or 'LON,LAT' in degrees")
    p.add_argument("--duration", default=None, help="simulated seconds (default 100; tanh 40)")
    p.add_argument("--errors", default="on", choices=("on", "off"),
                   help="the scenario's star sensor, gyro and wheel errors (default on)")
    p.add_argument("--disturbances", default=",".join(DISTURBANCES),
                   help=f"comma-separated, each switchable: {', '.join(DISTURBANCES)}, or 'none' (default all three; "
                        "solar radiation is off on both sides: Basilisk needs SPICE ephemerides for it)")
    add_scenario_argument(p)
    p.add_argument("--seed", default="0", help="noise seed (default 0)")
    p.add_argument("--t-img", default="1.0", help="imaging window length T_img in s (default 1)")
    p.add_argument("--settle", default="10.0", help="start of the first imaging window in s (default 10)")
    p.add_argument("--dt", default=None, help=f"tanh only: plant step in s (default {TANH_DEFAULT_DT:g}, as "
                   "`simulate --controller tanh-c`)")
    p.add_argument("--workers", default=None, help="worker processes for several targets (default: all cores)")
    p.add_argument("--verify-key", default=None, metavar="FILE",
                   help="the package's manifest must carry a valid HMAC-SHA256 signature under this key "
                        "(`generate --sign-key FILE`), else it is not loaded")
    p.add_argument("--compare", action="store_true",
                   help="also fly the same package in staregen's simulator and write the cross-check")
    p.add_argument("--out", default="out/basilisk", help="output folder (default out/basilisk)")
    p.set_defaults(func=main)


def _check_arguments(args) -> None:
    if args.controller not in CONTROLLERS:
        raise HostError(f"unknown controller {args.controller!r} for basilisk (one of: {', '.join(CONTROLLERS)})")
    if args.controller == "tanh":
        staring_only = [(n, v, d) for n, v, d in (("--target", args.target, "central"), ("--errors", args.errors, "on"),
                                                  ("--disturbances", args.disturbances, ",".join(DISTURBANCES)),
                                                  ("--seed", args.seed, "0"), ("--t-img", args.t_img, "1.0"),
                                                  ("--settle", args.settle, "10.0")) if v != d]
        staring_only += [(n, v, None) for n, v in (("--scenario", args.scenario), ("--workers", args.workers))
                         if v is not None]
        if staring_only:
            raise HostError(f"{staring_only[0][0]} does not apply to --controller tanh (paper 000's own example)")
    elif args.dt is not None:
        raise HostError("--dt applies to --controller tanh only (the staring scenario steps at 0.02 s)")
    else:
        parse_disturbances(args.disturbances)      # refused before Basilisk is imported or the package built


def main(args: argparse.Namespace) -> int:
    _check_arguments(args)
    out = Path(args.out)
    check_output_folder(out, OWNED, [args.package, args.scenario, args.verify_key])
    key = load_key(args.verify_key) if args.verify_key is not None else None
    basilisk.basilisk()                          # a missing extra: one line, before anything is built
    package = loaded_package(str(Path(args.package)), key)   # checked, built, self-tested; else one line
    if args.controller == "tanh":
        return run_tanh(args, package, out)
    return run_staring(args, package, out, key)


# ----------------------------------------------------------------------------- staring scenario

def parse_disturbances(text: str) -> DisturbanceParams | None:
    """staregen's disturbance model with the chosen torques on (the others at zero); None for 'none'."""
    names = [n.strip() for n in text.split(",")]
    if names == ["none"]:
        return None
    unknown = [n for n in names if n not in DISTURBANCES]
    if unknown or not names:
        raise HostError(f"--disturbances: unknown {shown(unknown[0] if unknown else text)} (any of "
                        f"{', '.join(DISTURBANCES)}, comma-separated, or 'none')")
    d = DisturbanceParams()
    return dataclasses.replace(d, srp_area=0.0, gravity_gradient="gravity-gradient" in names,
                               drag_area=d.drag_area if "drag" in names else 0.0,
                               residual_dipole=d.residual_dipole if "magnetic" in names else np.zeros(3))


def staring_config(args, scenario) -> SimConfig:
    errors = args.errors == "on"
    disturbances = parse_disturbances(args.disturbances)
    return SimConfig(duration=parse_number(args.duration or str(DEFAULT_DURATION_S), "--duration", positive=True,
                                           maximum=MAX_DURATION_S),
                     seed=parse_int(args.seed, "--seed"), errors=scenario.errors, sensor_errors=errors,
                     wheel_errors=errors, external_torques=disturbances is not None,
                     disturbances=disturbances or DisturbanceParams())


def _check_controller(package, controller: str, folder: str) -> None:
    if package.entries.get("controller") is None:
        raise HostError(f"package {folder} holds no controller unit")
    if controller == "pid" and not pid_only(package):
        raise HostError(f"package {folder}: its controller flies its network; for --controller pid generate one "
                        "with `staregen generate --pid-only`")
    if controller == "fig2" and pid_only(package):
        raise HostError(f"package {folder} was generated with --pid-only; fly it with --controller pid")


def _campaign(name, targets, cfg, plan, make, workers, engine) -> CampaignResult:
    start = time.perf_counter()
    histories = simulate_targets(make, [(tg.lon, tg.lat) for tg in targets], cfg, workers=workers,
                                 progress=len(targets) > 1, engine=engine)
    metrics = [staring_metrics(h.t, h.A_bd, h.omega_e, plan, t_end=cfg.control_steps * cfg.control_period)
               for h in histories]
    return CampaignResult(name, list(targets), cfg, plan, histories, metrics, average_metrics(metrics),
                          time.perf_counter() - start)


def run_staring(args, package, out: Path, key: bytes | None = None) -> int:
    _check_controller(package, args.controller, args.package)
    scenario = load_scenario(args.scenario)
    cfg, plan = staring_config(args, scenario), build_plan(args)
    targets = parse_target(args.target)
    plan.windows(cfg.control_steps * cfg.control_period)
    check_targets_visible(targets, cfg)
    workers = None if args.workers is None else parse_int(args.workers, "--workers", minimum=1)
    make = functools.partial(make_package_controller, str(Path(args.package)), args.controller, key)
    described = {**scenario.describe(), "simulator": f"Basilisk {basilisk.BSK_VERSION}",
                 "package": package.name, "disturbances": basilisk.disturbance_names(cfg)}
    print(f"{args.controller}: package {package.name} in Basilisk {basilisk.BSK_VERSION}, {len(targets)} target(s), "
          f"{cfg.control_steps * cfg.control_period:g} s, errors {args.errors} ...", flush=True)
    flown = _campaign(f"{args.controller} (Basilisk)", targets, cfg, plan, make, workers, basilisk.staring_run)
    check = None
    if args.compare:
        own = _campaign(f"{args.controller} (staregen)", targets, cfg, plan, make, workers, simulate)
        check = crosscheck.cross_check(own.histories, flown.histories, own.metrics, flown.metrics)
    with atomic.directory(out) as tmp:
        write_campaign(flown, tmp, described)
        if check is not None:
            atomic.write_json(tmp / "crosscheck.json", {
                "kind": "staring", "simulators": ["staregen", described["simulator"]], "controller": args.controller,
                "errors": args.errors, "disturbances": described["disturbances"],
                "duration_s": cfg.control_steps * cfg.control_period, **check.document()})
            a, b = own.histories[0], flown.histories[0]
            crosscheck.plot_overlay(a.t, [("A_bd [deg]", np.degrees(a.A_bd), np.degrees(b.A_bd)),
                                          ("omega_e [deg/s]", np.degrees(a.omega_e), np.degrees(b.omega_e))],
                                    tmp / "crosscheck_overlay.png",
                                    f"{args.controller}, {targets[0].name}: staregen (solid) and Basilisk (dashed)")
    print(format_table(flown))
    if check is not None:
        print("\n".join(crosscheck.summary_lines(check)))
    print(f"wrote {out}/metrics.json")
    return 0


# ----------------------------------------------------------------------------- paper 000's example

def _check_tanh_unit(package, folder: str) -> tuple[float, float]:
    """(period, torque bound) of the package's tanh unit, which must be paper 000's example law."""
    if "tanh" not in package.entries:
        raise HostError(f"package {folder} holds no tanh unit (generate with units = [..., \"tanh\"])")
    config = package.manifest.get("config")
    timing = config.get("timing") if isinstance(config, dict) else None
    period = timing.get("control_period") if isinstance(timing, dict) else None
    if isinstance(period, bool) or not isinstance(period, (int, float)) or not 1e-4 <= period <= 10.0:
        raise HostError(f"package {folder}: its manifest's config.timing.control_period is not a period in "
                        "[1e-4, 10] s")
    params = unit_registry.get("tanh").load_params(PAPER000_PARAMS)
    want = TanhUnit(params, period, name=f"{package.name}_tanh").identity()
    if package.manifest["units"]["tanh"].get("identity") != want:
        raise HostError(f"package {folder}: its tanh unit is not paper 000's example law ({PAPER000_PARAMS.name} at "
                        f"{period:g} s), which is the scenario this command flies")
    return float(period), params.k1 + params.k2 + params.k3


def run_tanh(args, package, out: Path) -> int:
    period, bound = _check_tanh_unit(package, args.package)
    duration = parse_number(args.duration or str(TANH_DEFAULT_DURATION_S), "--duration", positive=True,
                            maximum=MAX_DURATION_S)
    dt = parse_number(args.dt or str(TANH_DEFAULT_DT), "--dt", positive=True, minimum=1e-6, maximum=period)
    print(f"tanh: package {package.name} in Basilisk {basilisk.BSK_VERSION}, paper 000's example, T = {period:g} s, "
          f"{duration:g} s ...", flush=True)
    start = time.perf_counter()
    history = basilisk.tanh_run(PackageTanhLaw(package), period, duration, dt)
    metrics = {**tanh_example.metrics_of(history), "simulator": f"Basilisk {basilisk.BSK_VERSION}",
               "package": package.name, "period": period, "dt": dt, "duration": duration, "mode": "sampled",
               "settle_threshold": tanh_example.SETTLE_THRESHOLD, "torque_bound": bound,
               "torque_within_bound": bool(np.max(np.abs(history["u"])) <= bound),
               "runtime_s": round(time.perf_counter() - start, 3)}
    reference = None
    if args.compare:      # the same package object code, a fresh state, in staregen's plant
        law = PackageTanhLaw(package)
        reference = tanh_in_loop.fly(tanh_example.paper_scenario(), law.entry.step, period, duration, dt)
    if reference is not None:
        ts, tb = tanh_example.metrics_of(reference)["t_settle"], metrics["t_settle"]
        rel = None if ts is None or tb is None else (tb - ts) / ts
        metrics["crosscheck"] = {"t_settle_staregen": ts, "t_settle_basilisk": tb, "relative_difference": rel,
                                 "tolerance": TANH_SETTLE_TOLERANCE,
                                 "within": rel is not None and abs(rel) <= TANH_SETTLE_TOLERANCE,
                                 "max_abs_e_norm_difference": float(np.max(np.abs(
                                     np.linalg.norm(history["e"], axis=1)
                                     - np.linalg.norm(reference["e"], axis=1))))}
    with atomic.directory(out) as tmp:
        tanh_example.write_outputs(tmp, metrics, history)
        if reference is not None:
            ref = reference
            atomic.write_json(tmp / "crosscheck.json", {
                "kind": "tanh", "simulators": ["staregen", metrics["simulator"]], "controller": "tanh",
                "duration_s": duration, "dt_s": dt, "u_max": metrics["u_max"], "torque_bound": bound,
                "torque_within_bound": metrics["torque_within_bound"], **metrics["crosscheck"]})
            crosscheck.plot_overlay(history["t"], [("e", ref["e"], history["e"]), ("u [N*m]", ref["u"], history["u"])],
                                    tmp / "crosscheck_overlay.png",
                                    "tanh law, paper 000: staregen (solid) and Basilisk (dashed), the package's C in both")
    print(f"  t_settle (|e| < {tanh_example.SETTLE_THRESHOLD:g} to stay) {metrics['t_settle']} s, e_final "
          f"{metrics['e_final']:.3e}, max |u| {metrics['u_max']:.4g} N*m (bound {bound:g}: "
          + ("within" if metrics["torque_within_bound"] else "EXCEEDED") + ")")
    if reference is not None:
        c = metrics["crosscheck"]
        print(f"  staregen's simulator (the same C): t_settle {c['t_settle_staregen']} s; relative difference "
              f"{c['relative_difference']:+.2e} (tolerance ±{TANH_SETTLE_TOLERANCE:.0%}): "
              + ("within" if c["within"] else "NOT within"))
    print(f"wrote {out}/metrics.json")
    return 0
