"""`staregen simulate`: closed-loop staring simulation of one controller over central/all/LON,LAT.

Prints the metrics table and writes metrics.json, histories and plots into --out. Every input is
checked before anything runs; the output folder is built in a temporary sibling and moved into
place only when complete, so a failure leaves no partial output.
"""
from __future__ import annotations

import argparse
from pathlib import Path

from codegen import artifact as art
from codegen.units.gp.params import load_params as load_gp_params
from codegen.units.rbf.params import load_params as load_rbf_params
from host.sim import gp_example, rbf_example, tanh_example, tanh_in_loop
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
TANH_DEFAULT_DURATION_S = 40.0       # paper 000's example
RBF_PARAMS = Path(__file__).resolve().parents[2] / "docs" / "rbf_paper002.toml"
RBF_DEFAULT_DURATION_S = 1000.0      # paper 002, section 3.1
RBF_MAX_DURATION_S = 20_000.0        # ten hours of a 10 Hz loop in Python: a bound on time and memory
GP_PARAMS = Path(__file__).resolve().parents[2] / "docs" / "gp_paper004.toml"
GP_MAX_DURATION_S = 20_000.0
OWNED = json_marker_owner("metrics.json")   # an earlier simulation's folder: replaced as a whole


def register(subparsers) -> None:
    p = subparsers.add_parser("simulate", help="closed-loop staring simulation and J_A, J_w, J metrics",
                              description=__doc__.splitlines()[0])
    p.add_argument("--controller", default="pid",
                   help=f"controller ({', '.join(sorted(CONTROLLERS))}, or 'tanh' for the paper-000 "
                        "finite-time example, 'tanh-c' / 'tanh-arm' for it with the generated C in the loop: "
                        "SIL x86 / PIL ARM emulator; 'rbf' for paper 002's RBF adaptive law on its tracking "
                        "scenario, 'rbf-c' / 'rbf-arm' for its generated C in the loop; 'gp-baseline' / 'gp' for "
                        "paper 004's attitude takeover under the baseline PD / the sparse-GP law, 'gp-c' / 'gp-arm' "
                        "for the GP law's generated C in the loop; default pid)")
    p.add_argument("--period", default=None,
                   help="tanh and rbf only: control period in s (zero-order hold); tanh: omitted = continuous "
                        "reference; rbf: default 0.1")
    p.add_argument("--dt", default=None, help="tanh and rbf only: plant RK4 step in s (default 5e-4; rbf 0.01)")
    p.add_argument("--params", default=None, metavar="FILE",
                   help="rbf and gp only: the law's parameter file (rbf: default docs/rbf_paper002.toml, theorem 2; "
                        "docs/rbf_paper002_theorem1.toml for theorem 1; gp: default docs/gp_paper004.toml, M = 20)")
    p.add_argument("--start", default=None, choices=gp_example.STARTS,
                   help="gp-baseline, gp, gp-c and gp-arm only: 'capture' (default, the post-capture state) or 'outside' "
                        "(60 deg off, outside the GP's training data: the paper's Fig. 7)")
    p.add_argument("--artifact", default=None, metavar="FILE",
                   help="model artifact for the network controllers (nn, nn-c, pid-c, nn-arm); "
                        "default: a stand-in network fitted to the PID law")
    p.add_argument("--baselines", default=None, metavar="FILE",
                   help="fitted baselines for pdff / linear (network.baselines.json from train or the pipeline)")
    p.add_argument("--tables", default=None, metavar="FILE",
                   help="discrete-point tables for dp / dp-c (`staregen dp build`)")
    p.add_argument("--target", default="central",
                   help="'central' (120E 30N), 'all' (the 100 seeded targets) or 'LON,LAT' in degrees")
    p.add_argument("--duration", default=None, help="simulated seconds (default 100; tanh 40, rbf 1000, gp 600)")
    p.add_argument("--seed", default="0", help="noise seed (default 0)")
    add_scenario_argument(p)
    p.add_argument("--t-img", default="1.0", help="imaging window length T_img in s (default 1)")
    p.add_argument("--settle", default="10.0", help="start of the first imaging window in s (default 10)")
    p.add_argument("--workers", default=None, help="worker processes for several targets (default: all cores)")
    p.add_argument("--out", default="out/simulate", help="output folder (default out/simulate)")
    p.set_defaults(func=main)


def build_config(args, errors) -> SimConfig:
    duration = args.duration if args.duration is not None else str(DEFAULT_DURATION_S)
    return SimConfig(duration=parse_number(duration, "--duration", positive=True, maximum=MAX_DURATION_S),
                     seed=parse_int(args.seed, "--seed"), errors=errors)


def build_plan(args) -> ImagingPlan:
    return ImagingPlan(T_img=parse_number(args.t_img, "--t-img", positive=True),
                       t_first=parse_number(args.settle, "--settle", non_negative=True))


def run_tanh_example(args: argparse.Namespace) -> int:
    """The paper-000 example (section 4.2) flown by the tanh saturation law; metrics.json + Figs. 5-8.
    tanh: the float64 law (continuous without --period); tanh-c / tanh-arm: the generated C in the
    loop (SIL / PIL, --period default 0.1 s) compared with the float64 sampled run."""
    duration = parse_number(str(TANH_DEFAULT_DURATION_S) if args.duration is None else args.duration, "--duration",
                            positive=True, maximum=MAX_DURATION_S)
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


def run_rbf_example(args: argparse.Namespace) -> int:
    """Paper 002's tracking scenario (260 m -> 100 m, line-of-sight tracking of a tumbling, manoeuvring
    target) flown by the RBF law: float64 (rbf) or the generated C in the loop (rbf-c, rbf-arm)."""
    if args.target != "central" or args.scenario is not None:
        raise HostError("--target and --scenario do not apply to the rbf controllers (paper 002's own scenario)")
    params = load_rbf_params(args.params if args.params is not None else RBF_PARAMS)
    duration = parse_number(str(RBF_DEFAULT_DURATION_S) if args.duration is None else args.duration, "--duration",
                            positive=True, maximum=RBF_MAX_DURATION_S)
    period = parse_number(args.period or "0.1", "--period", minimum=0.01, maximum=1.0)
    dt = parse_number(args.dt or "0.01", "--dt", minimum=MIN_DT_S, maximum=period)
    out = Path(args.out)
    check_output_folder(out, OWNED, [args.params])
    try:
        with atomic.directory(out) as tmp:
            m = rbf_example.run(args.controller, params, duration, period, dt, out_dir=tmp)["metrics"]
    except OSError as exc:
        raise HostError(f"cannot write output folder {out}: {exc.strerror or exc}") from None
    print("\n".join(rbf_summary(m)))
    print(f"wrote {out}/metrics.json")
    return 0


def rbf_summary(m: dict) -> list[str]:
    att = m["t_attitude_1deg"]
    lines = [f"{m['controller']}: paper 002 tracking scenario, theorem {m['theorem']}, T = {m['period']:g} s, "
             f"{m['duration']:g} s" + (f", {m['mode']}" if "mode" in m else ""),
             f"  range within 5 m / 1 m of 100 m (to stay) {rbf_example.format_seconds(m['t_rho_5m'])} / {rbf_example.format_seconds(m['t_rho_1m'])}"
             f"   (paper: 22.9 s); closest approach {m['min_rho']:.1f} m at {m['t_min_rho']:.1f} s",
             "  attitude within 1 deg (phi, theta, psi)   " + ", ".join(rbf_example.format_seconds(x) for x in att)
             + "   (paper: 5.7 s)",
             f"  delta-v {m['delta_v']:.1f} m/s, torque impulse {m['torque_impulse']:.2f} N*m*s, "
             f"weight bound active {m['weight_bound_active_steps']} steps"]
    if "rms_e1" in m:
        lines.append("  RMS error over [%g, %g] s: rho %.2e m, LOS %.2e %.2e rad, attitude %.2e %.2e %.2e rad"
                     % (*m["accuracy_window"], *m["rms_e1"]))
    if "golden_mismatch_steps" in m:
        lines.append(f"  golden mismatches {m['golden_mismatch_steps']} steps; against float64: max |d rho| "
                     f"{m['max_rho_diff_m']:.2e} m, max |d attitude| {m['max_attitude_diff_deg']:.2e} deg")
    if "cycles_max" in m:
        lines.append(f"  cycles per step (ideal memory): median {m['cycles_median']}, max {m['cycles_max']}")
    return lines


def _refuse_for_gp(args) -> None:
    """One line for an option the takeover scenario does not use (its own plant, period and start)."""
    given = [(name, value) for name, value in (("--period", args.period), ("--dt", args.dt),
                                                ("--artifact", args.artifact), ("--baselines", args.baselines),
                                                ("--tables", args.tables), ("--scenario", args.scenario),
                                                ("--workers", args.workers)) if value is not None]
    defaults = (("--target", args.target, "central"), ("--seed", args.seed, "0"), ("--t-img", args.t_img, "1.0"),
                ("--settle", args.settle, "10.0"))
    given = [(name, value) for name, value, default in defaults if value != default] + given
    if given:
        raise HostError(f"{given[0][0]} does not apply to --controller {args.controller} "
                        "(paper 004's takeover scenario: its own plant, T = 0.1 s, RK4 0.01 s)")


def run_gp_example(args: argparse.Namespace) -> int:
    """Paper 004's attitude takeover (section 1) flown by the baseline PD or the GP law of the law's file."""
    _refuse_for_gp(args)
    params = load_gp_params(args.params if args.params is not None else GP_PARAMS)
    duration = parse_number(str(gp_example.DEFAULT_DURATION) if args.duration is None else args.duration,
                            "--duration", positive=True, maximum=GP_MAX_DURATION_S)
    start = args.start or "capture"
    out = Path(args.out)
    check_output_folder(out, OWNED, [args.params])
    print(f"{args.controller}: paper 004 takeover, start {start}, {duration:g} s, M = {params.n_inducing} ...",
          flush=True)
    try:
        with atomic.directory(out) as tmp:
            record = {"params": str(args.params if args.params is not None else GP_PARAMS)}
            m = gp_example.run(args.controller, params, duration, start, out_dir=tmp, record=record)["metrics"]
    except OSError as exc:
        raise HostError(f"cannot write output folder {out}: {exc.strerror or exc}") from None
    print("\n".join(gp_summary(m)))
    print(f"wrote {out}/metrics.json")
    return 0


def _band(x) -> str:
    return rbf_example.format_seconds(x)


def gp_summary(m: dict) -> list[str]:
    lines = [f"  error within 1 deg / 0.1 deg (to stay) {_band(m['t_settle_1deg'])} / {_band(m['t_settle_0p1deg'])}; "
             f"last 60 s mean {m['steady_error_deg_mean']:.3g} deg, max {m['steady_error_deg_max']:.3g} deg",
             "  torque RMS " + ", ".join(f"{v:.3f}" for v in m["torque_rms"]) + f" N*m, max |u| {m['max_abs_torque']:.3f}",
             "  wheel momentum at the end " + ", ".join(f"{v:.1f}" for v in m["h_w_end"]) + " N*m*s; 50 N*m*s at "
             + ", ".join("-" if v is None else f"{v:.0f} s" for v in m["t_momentum_limit"]),
             "  gains (K1, K2) first / last 60 s " + ", ".join(f"{v:.2f}" for v in m["gains_first_60s"]) + " / "
             + ", ".join(f"{v:.2f}" for v in m["gains_last_60s"])]
    if "golden_mismatch_steps" in m:
        lines.append(f"  {m['mode']}: {m['golden_mismatch_steps']} steps differ from the golden model; against "
                     f"float64: |d angle| <= {m['max_angle_diff_deg']:.2e} deg, |d torque| <= {m['max_torque_diff']:.2e} "
                     f"N*m, |d mu| <= {m['max_mu_diff']:.2e} N*m")
    if "cycles_max" in m:
        lines.append(f"  cycles per step (ideal memory) min {m['cycles_min']}, median {m['cycles_median']}, "
                     f"max {m['cycles_max']}")
    if m["var_fraction_first_60s"] is not None:
        lines.append(f"  variance fraction s first / last 60 s {m['var_fraction_first_60s']:.3g} / "
                     f"{m['var_fraction_last_60s']:.3g} (max {m['var_fraction_max']:.3g}); GP mean RMS error "
                     + ", ".join(f"{v:.2e}" for v in m["mu_rms_error"]) + " N*m")
    return lines


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
    if args.controller in gp_example.CONTROLLERS:
        return run_gp_example(args)
    if args.start is not None:
        raise HostError(f"--start applies to --controller {', '.join(gp_example.CONTROLLERS)} only")
    if args.controller in rbf_example.CONTROLLERS:
        return run_rbf_example(args)
    if args.params is not None:
        raise HostError("--params applies to --controller rbf, rbf-c, rbf-arm, gp-baseline, gp, gp-c, gp-arm only")
    if args.controller in ("tanh", "tanh-c", "tanh-arm"):
        return run_tanh_example(args)
    if args.period is not None or args.dt is not None:
        raise HostError("--period and --dt apply to --controller tanh and rbf only")
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
