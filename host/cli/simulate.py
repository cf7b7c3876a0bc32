"""`staregen simulate`: closed-loop staring simulation of one controller over central/all/LON,LAT.

Prints the metrics table and writes metrics.json, histories and plots into --out. Every input is
checked before anything runs; the output folder is built in a temporary sibling and moved into
place only when complete, so a failure leaves no partial output.
"""
from __future__ import annotations

import argparse
from pathlib import Path

from codegen import artifact as art
from host.sim import tanh_example, tanh_in_loop
from host.cli.args import add_scenario_argument, load_scenario, parse_int, parse_number
from host.sim.campaign import format_table, run_campaign, validate_campaign, write_campaign
from host.control.baselines import load_baselines
from host.control.controllers import ARTIFACT_CONTROLLERS, BASELINE_CONTROLLERS, CONTROLLERS, DP_CONTROLLERS
from host.control.dp_controller import load_tables
from host.errors import HostError
from host.outputs import check_output_folder, json_marker_owner
from host.sim.metrics import ImagingPlan
from host.sim.simulator import SimConfig
from host.sim.targets import parse_target
from codegen import atomic

DEFAULT_DURATION_S = 100.0
MAX_DURATION_S = 100_000.0    # a staring pass lasts minutes; this bounds memory (histories) too
MIN_PERIOD_S, MAX_PERIOD_S = 1e-4, 10.0
MIN_DT_S = 1e-6
OWNED = json_marker_owner("metrics.json")   # an earlier simulation's folder: replaced as a whole


def register(subparsers) -> None:
    p = subparsers.add_parser("simulate", help="closed-loop staring simulation and J_A, J_w, J metrics",
                              description=__doc__.splitlines()[0])
    p.add_argument("--controller", default="pid",
                   help=f"controller ({', '.join(sorted(CONTROLLERS))}, or 'tanh' for the paper-000 "
                        "finite-time example, 'tanh-c' / 'tanh-arm' for it with the generated C in the loop: "
                        "SIL x86 / PIL ARM emulator; default pid)")
    p.add_argument("--period", default=None,
                   help="tanh only: control period in s (zero-order hold); omitted = continuous reference")
    p.add_argument("--dt", default=None, help="tanh only: plant RK4 step in s (default 5e-4)")
    p.add_argument("--artifact", default=None, metavar="FILE",
                   help="model artifact for the network controllers (nn, nn-c, pid-c, nn-arm); "
                        "default: a stand-in network fitted to the PID law")
    p.add_argument("--baselines", default=None, metavar="FILE",
                   help="fitted baselines for pdff / linear (network.baselines.json from train or the pipeline)")
    p.add_argument("--tables", default=None, metavar="FILE",
                   help="discrete-point tables for dp / dp-c (`staregen dp build`)")
    p.add_argument("--target", default="central",
                   help="'central' (120E 30N), 'all' (the 100 seeded targets) or 'LON,LAT' in degrees")
    p.add_argument("--duration", default=str(DEFAULT_DURATION_S), help="simulated seconds (default 100)")
    p.add_argument("--seed", default="0", help="noise seed (default 0)")
    add_scenario_argument(p)
    p.add_argument("--t-img", default="1.0", help="imaging window length T_img in s (default 1)")
    p.add_argument("--settle", default="10.0", help="start of the first imaging window in s (default 10)")
    p.add_argument("--workers", default=None, help="worker processes for several targets (default: all cores)")
    p.add_argument("--out", default="out/simulate", help="output folder (default out/simulate)")
    p.set_defaults(func=main)


def build_config(args, errors) -> SimConfig:
    return SimConfig(duration=parse_number(args.duration, "--duration", positive=True, maximum=MAX_DURATION_S),
                     seed=parse_int(args.seed, "--seed"), errors=errors)


def build_plan(args) -> ImagingPlan:
    return ImagingPlan(T_img=parse_number(args.t_img, "--t-img", positive=True),
                       t_first=parse_number(args.settle, "--settle", non_negative=True))


def run_tanh_example(args: argparse.Namespace) -> int:
    """The paper-000 example (section 4.2) flown by the tanh saturation law; metrics.json + Figs. 5-8.
    tanh: the float64 law (continuous without --period); tanh-c / tanh-arm: the generated C in the
    loop (SIL / PIL, --period default 0.1 s) compared with the float64 sampled run."""
    duration = parse_number(args.duration if args.duration != str(DEFAULT_DURATION_S) else "40",
                            "--duration", positive=True, maximum=MAX_DURATION_S)
    in_loop = {"tanh-c": "x86", "tanh-arm": "arm"}.get(args.controller)
    period = None if args.period is None else parse_number(args.period, "--period", minimum=MIN_PERIOD_S,
                                                              maximum=MAX_PERIOD_S)
    if in_loop and period is None:
        period = 0.1
    dt = parse_number(args.dt or str(tanh_example.MAX_REFERENCE_STEP), "--dt", positive=True, minimum=MIN_DT_S,
                      maximum=MAX_PERIOD_S)
    out = Path(args.out)
    check_output_folder(out, OWNED)
    try:
        with atomic.directory(out) as tmp:
            if in_loop:
                result = tanh_in_loop.run_in_loop(in_loop, period, duration, dt, out_dir=tmp)
            else:
                result = tanh_example.run(period, duration, dt, out_dir=tmp)
    except OSError as exc:
        raise HostError(f"cannot write output folder {out}: {exc.strerror or exc}") from None
    m = result["metrics"]
    mode = "continuous (RK4 %g s)" % dt if period is None else "sampled every %g s" % period
    print(f"tanh law, paper-000 example, {mode}, {duration:g} s" + (f", {m['mode']}" if in_loop else ""))
    keys = [("t_settle", "s"), ("e_final", ""), ("we_final", "rad/s"), ("u_max", "N*m")]
    if in_loop:
        keys += [("golden_mismatch_steps", ""), ("e_diff_max", ""), ("e_diff_after_25s", ""),
                 ("e_diff_float64_self_max", "")]
        keys += [("cycles_median", ""), ("cycles_max", "")] if in_loop == "arm" else []
    for key, unit in keys:
        print(f"  {key:21s} {m[key]!s:>22} {unit}")
    print(f"wrote {out}/metrics.json")
    return 0


def controller_options(args) -> dict:
    """Factory options: the artifact of a network controller, the baselines file of a fitted
    baseline (each checked here: a clear user error)."""
    baselines = getattr(args, "baselines", None)   # commands without --baselines (impulse) fly no baseline
    tables = getattr(args, "tables", None)
    if tables is not None and args.controller not in DP_CONTROLLERS:
        raise HostError(f"--tables applies to {', '.join(DP_CONTROLLERS)} only")
    if args.controller in DP_CONTROLLERS:
        if args.artifact is not None or baselines is not None:
            raise HostError(f"--artifact and --baselines do not apply to {args.controller}")
        if tables is None:
            raise HostError(f"controller {args.controller} needs --tables FILE (written by `staregen dp build`)")
        load_tables(tables)   # a missing or invalid file is reported before anything runs
        return {"tables": tables}
    if baselines is not None and args.controller not in BASELINE_CONTROLLERS:
        raise HostError(f"--baselines applies to {', '.join(BASELINE_CONTROLLERS)} only")
    if args.controller in BASELINE_CONTROLLERS:
        if args.artifact is not None:
            raise HostError(f"--artifact applies to {', '.join(ARTIFACT_CONTROLLERS)} only")
        if baselines is not None:
            load_baselines(baselines)   # a missing or invalid file is reported before anything runs
        return {"baselines": baselines}
    if args.controller not in ARTIFACT_CONTROLLERS:
        if args.artifact is not None:
            raise HostError(f"--artifact applies to {', '.join(ARTIFACT_CONTROLLERS)} only")
        return {}
    if args.artifact is not None:
        art.load(args.artifact)   # a missing or invalid file is reported before anything runs
    return {"artifact": args.artifact}


def main(args: argparse.Namespace) -> int:
    if args.controller in ("tanh", "tanh-c", "tanh-arm"):
        return run_tanh_example(args)
    if args.period is not None or args.dt is not None:
        raise HostError("--period and --dt apply to --controller tanh only")
    targets = parse_target(args.target)
    scenario = load_scenario(args.scenario)
    config, plan = build_config(args, scenario.errors), build_plan(args)
    workers = None if args.workers is None else parse_int(args.workers, "--workers", minimum=1)
    options = controller_options(args)
    out = Path(args.out)
    check_output_folder(out, OWNED, [args.artifact, args.baselines, args.tables, args.scenario])
    validate_campaign(args.controller, targets, config, plan, options)
    try:
        with atomic.directory(out) as tmp:
            result = run_campaign(args.controller, targets, config, plan, workers=workers, options=options)
            write_campaign(result, tmp, scenario.describe())
    except OSError as exc:
        raise HostError(f"cannot write output folder {out}: {exc.strerror or exc}") from None
    print(format_table(result))
    print(f"wrote {out}/metrics.json")
    return 0
