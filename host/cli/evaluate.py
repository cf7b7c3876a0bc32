"""`staregen evaluate`: paper 001 §7's comparisons (Tables 8-11, Figs. 10-15) for the network, the
PID with Table 1 gains, the tuned PID and the PD + feed-forward baseline; evaluate.json + PNGs.

  --network FILE       the trained artifact (its baselines file next to it is used for PD+FF)
  --tuned FILE         a controller.toml from `staregen tune pid` (adds the tuned PID row)
  --sil / --pil        add the generated C in the loop: SIL over the targets, PIL on the central one
  --scenario FILE      the reading of Table 6's errors (default `table6`), recorded in evaluate.json
  --quick              the small preset (3 targets × 20 s, one step-response target, two frequencies),
                       flagged as not comparable with the paper in evaluate.json and the report
Paper scale by default: 100 targets × 100 s staring, the step response over the 100, nine
frequencies, on the batched simulator (--engine scalar flies the scalar reference instead).
"""
from __future__ import annotations

import argparse
from pathlib import Path

from codegen import artifact as art
from codegen.package import config as pc
from host.cli.args import add_scenario_argument, load_scenario, parse_int, parse_number, parse_response_targets
from host.cli.tune import parse_targets
from host.control.baselines import load_baselines
from host.errors import HostError
from host.learn.training import baselines_path
from host.control.dp_controller import load_tables
from host.sim.campaign import check_targets_visible
from host.sim.simulator import SimConfig
from host.sim.targets import Target, central_target
from host.tune import figures
from host.tune.evaluate import ENGINES, QUICK, ControllerSpec, EvalPlan, evaluate, table1_spec, tuned_spec


def register(subparsers) -> None:
    p = subparsers.add_parser("evaluate", help="paper 001 §7 comparisons: staring, step, frequency, impulse",
                              description=__doc__.splitlines()[0])
    p.add_argument("--network", required=True, metavar="FILE", help="trained 12-40-3 artifact")
    p.add_argument("--baselines", default=None, metavar="FILE",
                   help="fitted baselines (default: <network>.baselines.json when it exists)")
    p.add_argument("--tuned", default=None, metavar="FILE", help="controller.toml with tuned PID gains")
    p.add_argument("--dp-tables", default=None, metavar="FILE",
                   help="discrete-point tables (`staregen dp build`): adds the paper-003 law (and its C with --sil)")
    p.add_argument("--targets", default="all",
                   help="staring targets: all, central, N (the first N of the 100) or a target list file")
    p.add_argument("--response-targets", default="all",
                   help="targets averaged in the step response: all (default: every staring target) or N (the first N)")
    p.add_argument("--duration", default="100", help="staring run length in s (default 100)")
    p.add_argument("--freqs", default="0.02,0.05,0.1,0.2,0.5,1,2,3,4.5", help="frequency grid in Hz")
    p.add_argument("--seed", default="0", help="noise seed (default 0)")
    p.add_argument("--controllers", default=None,
                   help="comma-separated subset of " + ", ".join(KEYS) + " (default: every one available)")
    p.add_argument("--sil", action="store_true", help="add the generated C (x86, cffi) over the targets")
    p.add_argument("--pil", action="store_true", help="add the generated C in the ARM emulator, central target")
    add_scenario_argument(p)
    p.add_argument("--quick", action="store_true",
                   help="small preset: 3 targets x 20 s, 1 step-response target, 2 frequencies (not comparable)")
    p.add_argument("--engine", default="batched", choices=ENGINES,
                   help="batched (default) or the scalar reference simulator")
    p.add_argument("--workers", default=None, help="worker processes of the scalar runs (default: all cores)")
    p.add_argument("--no-progress", action="store_true", help="no progress bars")
    p.add_argument("--out", required=True, help="output folder (created)")
    p.set_defaults(func=run)


# --controllers names -> labels of the specs below
KEYS = {"pid": "PID (Table 1)", "pid-tuned": "PID (tuned)", "nn": "NN (float64)", "nn-c": "NN (SIL, x86 C)",
        "nn-arm": "NN (PIL, ARM, central)", "pdff": "PD+FF", "dp": "DP (float64)", "dp-c": "DP (SIL, x86 C)"}


def select(specs: list[ControllerSpec], text: str | None) -> list[ControllerSpec]:
    """The specs named by --controllers (each must be known and available with the given inputs)."""
    if text is None:
        return specs
    names = [n.strip() for n in text.split(",") if n.strip()]
    if not names:
        raise HostError("--controllers lists no controller")
    for n in names:
        if n not in KEYS:
            raise HostError(f"unknown controller {n!r} (known: {', '.join(KEYS)})")
    available = {s.label for s in specs}
    missing = [n for n in names if KEYS[n] not in available]
    if missing:
        raise HostError(f"--controllers {', '.join(missing)}: not available with these inputs "
                        "(pid-tuned needs --tuned, nn-c --sil, nn-arm --pil, pdff a baselines file, dp --dp-tables, "
                        "dp-c --dp-tables and --sil)")
    wanted = {KEYS[n] for n in names}
    return [s for s in specs if s.label in wanted]


def controller_specs(args) -> list[ControllerSpec]:
    a = art.load(args.network)   # a missing or invalid file is reported before anything runs
    if a.sizes[0] != 12 or a.sizes[-1] != 3:
        raise HostError(f"--network: the network controller needs a 12-input, 3-output network, got {a.shape_text}")
    specs = [table1_spec()]
    if args.tuned:
        c = pc.load(args.tuned).controller
        specs.append(tuned_spec(c.kp, c.ki, c.kd))
    specs.append(ControllerSpec("NN (float64)", "nn", (("artifact", args.network),)))
    if args.sil:
        specs.append(ControllerSpec("NN (SIL, x86 C)", "nn-c", (("artifact", args.network),)))
    if args.pil:
        specs.append(ControllerSpec("NN (PIL, ARM, central)", "nn-arm", (("artifact", args.network),)))
    laws = args.baselines or (str(baselines_path(args.network)) if baselines_path(args.network).exists() else None)
    if laws:
        load_baselines(laws)
        specs.append(ControllerSpec("PD+FF", "pdff", (("baselines", laws),)))
    if args.dp_tables:
        load_tables(args.dp_tables)   # a missing or invalid file is reported before anything runs
        specs.append(ControllerSpec("DP (float64)", "dp", (("tables", args.dp_tables),)))
        if args.sil:
            specs.append(ControllerSpec("DP (SIL, x86 C)", "dp-c", (("tables", args.dp_tables),)))
    return select(specs, args.controllers)


def parse_freqs(text: str) -> tuple[float, ...]:
    parts = [p for p in text.split(",") if p.strip()]
    if not parts:
        raise HostError("--freqs needs at least one frequency")
    return tuple(parse_number(p, "--freqs", positive=True, maximum=4.99) for p in parts)


def build_plan(args, errors) -> EvalPlan:
    """The evaluation plan from the arguments: paper scale, or the --quick preset."""
    c = central_target()
    central = (c.name, c.lon, c.lat, 0)
    if args.quick:
        targets = parse_targets(str(QUICK["targets"]))
        return EvalPlan(targets=targets, response_targets=targets[:QUICK["response_targets"]], central=central,
                        duration=QUICK["duration"], seed=parse_int(args.seed, "--seed", maximum=2**32 - 1),
                        freqs=QUICK["freqs"], freq_duration=QUICK["freq_duration"], errors=errors,
                        engine=args.engine, preset="quick")
    targets = parse_targets(args.targets)
    n_resp = parse_response_targets(args.response_targets, len(targets))
    return EvalPlan(targets=targets, response_targets=targets[:n_resp], central=central,
                    duration=parse_number(args.duration, "--duration", minimum=11.0, maximum=86400.0),
                    seed=parse_int(args.seed, "--seed", maximum=2**32 - 1), freqs=parse_freqs(args.freqs),
                    errors=errors, engine=args.engine)


def run(args: argparse.Namespace) -> int:
    scenario = load_scenario(args.scenario)
    plan = build_plan(args, scenario.errors)
    workers = None if args.workers is None else parse_int(args.workers, "--workers", minimum=1, maximum=256)
    check_targets_visible([Target(n, lon, lat) for n, lon, lat, _ in plan.targets], SimConfig(duration=plan.duration))
    specs = controller_specs(args)
    out = Path(args.out)
    if out.exists() and not out.is_dir():
        raise HostError(f"output folder {out} exists and is not a directory")
    result = evaluate(plan, specs, workers, progress=not args.no_progress)
    result["scenario"] = scenario.describe()
    result = figures.write_evaluation(result, args.network, plan.seed, out, scenario.errors)
    print(summary(result))
    print(f"wrote {out}/evaluate.json and 4 figures")
    return 0


def summary(result: dict) -> str:
    lines = [f"{'controller':26s} {'targets':>7s} {'J_A [°]':>10s} {'J_w [°/s]':>10s} {'J':>10s}"]
    for label, r in result["staring"].items():
        lines.append(f"{label:26s} {r['targets']:7d} {r['J_A']:10.3e} {r['J_w']:10.3e} {r['J']:10.3e}")
    lines.append("step response (mean over targets; x, y, z): overshoot %, settling s, steady-state error °")
    for label, s in result["step"].items():
        m = s["mean"]
        lines.append(f"  {label:24s} " + "  ".join(
            f"{k.split('_')[0]} " + ", ".join(f"{v:.3g}" for v in m[k]) for k in m))
    return "\n".join(lines)
