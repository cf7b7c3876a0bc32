"""`staregen simulate`: closed-loop staring simulation of one controller over central/all/LON,LAT.

Prints the metrics table and writes metrics.json, histories and plots into --out. Every input is
checked before anything runs; the output folder is built in a temporary sibling and moved into
place only when complete, so a failure leaves no partial output.
"""
from __future__ import annotations

import argparse
import math
from pathlib import Path

from host.campaign import format_table, run_campaign, validate_campaign, write_campaign
from host.controllers import CONTROLLERS
from host.errors import HostError
from host.metrics import ImagingPlan
from host.simulator import SimConfig
from host.targets import parse_target
from tools import atomic

DEFAULT_DURATION_S = 100.0


def register(subparsers) -> None:
    p = subparsers.add_parser("simulate", help="closed-loop staring simulation and J_A, J_w, J metrics",
                              description=__doc__.splitlines()[0])
    p.add_argument("--controller", default="pid",
                   help=f"controller ({', '.join(sorted(CONTROLLERS))}, or 'tanh' for the paper-000 "
                        "finite-time example; default pid)")
    p.add_argument("--period", default=None,
                   help="tanh only: control period in s (zero-order hold); omitted = continuous reference")
    p.add_argument("--dt", default=None, help="tanh only: plant RK4 step in s (default 5e-4)")
    p.add_argument("--target", default="central",
                   help="'central' (120E 30N), 'all' (the 100 seeded targets) or 'LON,LAT' in degrees")
    p.add_argument("--duration", default=str(DEFAULT_DURATION_S), help="simulated seconds (default 100)")
    p.add_argument("--seed", default="0", help="noise seed (default 0)")
    p.add_argument("--t-img", default="1.0", help="imaging window length T_img in s (default 1)")
    p.add_argument("--settle", default="10.0", help="start of the first imaging window in s (default 10)")
    p.add_argument("--workers", default=None, help="worker processes for several targets (default: all cores)")
    p.add_argument("--out", default="out/simulate", help="output folder (default out/simulate)")
    p.set_defaults(func=main)


def parse_number(text: str, what: str, *, positive: bool = False, non_negative: bool = False) -> float:
    try:
        value = float(text)
    except (TypeError, ValueError):
        raise HostError(f"{what} must be a number, got {text!r}") from None
    if not math.isfinite(value):
        raise HostError(f"{what} must be finite, got {text!r}")
    if positive and value <= 0:
        raise HostError(f"{what} must be positive, got {text}")
    if non_negative and value < 0:
        raise HostError(f"{what} must not be negative, got {text}")
    return value


def parse_int(text: str, what: str, minimum: int = 0) -> int:
    try:
        value = int(text)
    except (TypeError, ValueError):
        raise HostError(f"{what} must be an integer, got {text!r}") from None
    if value < minimum:
        raise HostError(f"{what} must be at least {minimum}, got {value}")
    return value


def check_output_folder(out: Path, marker: str = "metrics.json") -> None:
    """The folder must be creatable or replaceable: not a file, its parent a directory, and, if it
    exists with content, a previous output of this command (holding `marker`) — the atomic
    write replaces the whole folder, so `--out ~` must never be accepted."""
    if out.exists() and not out.is_dir():
        raise HostError(f"output folder {out} exists and is not a directory")
    if out.is_dir() and any(out.iterdir()) and not (out / marker).is_file():
        raise HostError(f"output folder {out} exists, is not empty and holds no {marker}; "
                        "refusing to replace it (choose a new or empty folder)")
    parent = out.resolve().parent
    for p in [parent, *parent.parents]:
        if p.exists():
            if not p.is_dir():
                raise HostError(f"cannot create output folder {out}: {p} is not a directory")
            break


def build_config(args) -> SimConfig:
    return SimConfig(duration=parse_number(args.duration, "--duration", positive=True),
                     seed=parse_int(args.seed, "--seed"))


def build_plan(args) -> ImagingPlan:
    return ImagingPlan(T_img=parse_number(args.t_img, "--t-img", positive=True),
                       t_first=parse_number(args.settle, "--settle", non_negative=True))


def run_tanh_example(args: argparse.Namespace) -> int:
    """The paper-000 example (section 4.2) flown by the tanh saturation law; metrics.json + Figs. 5-8."""
    from host import tanh_example  # the staring scenario does not need it

    duration = parse_number(args.duration if args.duration != str(DEFAULT_DURATION_S) else "40",
                            "--duration", positive=True)
    period = None if args.period is None else parse_number(args.period, "--period", positive=True)
    dt = parse_number(args.dt or str(tanh_example.MAX_REFERENCE_STEP), "--dt", positive=True)
    out = Path(args.out)
    check_output_folder(out)
    try:
        with atomic.directory(out) as tmp:
            result = tanh_example.run(period, duration, dt, out_dir=tmp)
    except OSError as exc:
        raise HostError(f"cannot write output folder {out}: {exc.strerror or exc}") from None
    m = result["metrics"]
    mode = "continuous (RK4 %g s)" % dt if period is None else "sampled every %g s" % period
    print(f"tanh law, paper-000 example, {mode}, {duration:g} s")
    for key, unit in (("t_settle", "s"), ("e_final", ""), ("we_final", "rad/s"), ("u_max", "N*m")):
        print(f"  {key:9s} {m[key]!s:>14} {unit}")
    print(f"wrote {out}/metrics.json")
    return 0


def main(args: argparse.Namespace) -> int:
    if args.controller == "tanh":
        return run_tanh_example(args)
    if args.period is not None or args.dt is not None:
        raise HostError("--period and --dt apply to --controller tanh only")
    targets = parse_target(args.target)
    config, plan = build_config(args), build_plan(args)
    workers = None if args.workers is None else parse_int(args.workers, "--workers", minimum=1)
    out = Path(args.out)
    check_output_folder(out)
    validate_campaign(args.controller, targets, config, plan)
    try:
        with atomic.directory(out) as tmp:
            result = run_campaign(args.controller, targets, config, plan, workers=workers)
            write_campaign(result, tmp)
    except OSError as exc:
        raise HostError(f"cannot write output folder {out}: {exc.strerror or exc}") from None
    print(format_table(result))
    print(f"wrote {out}/metrics.json")
    return 0
