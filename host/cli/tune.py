"""`staregen tune pid`: the paper's Table 7 PID grid over the staring targets on the batched
simulator (Dask: a local cluster or --scheduler), sharded and resumable; the best triple per axis
goes into a controller configuration (OUT/controller.toml) that `staregen generate` flies.

  --grid coarse|table7|kp=LO:HI:STEP,ki=..,kd=..   60 triples (CI, the pipeline), the paper's 12,240, or your own
  --targets all|central|N|FILE   the 100 staring targets, the central one, the first N of the 100, or a
                        target list file (NAME,LON,LAT or LON,LAT per line, degrees)
"""
from __future__ import annotations

import argparse
from pathlib import Path

from codegen.package import config as pc
from host.cli.args import add_scenario_argument, load_scenario, parse_int, parse_number
from host.control.nn_controller import default_package_config
from host.errors import HostError
from host.sim.campaign import check_targets_visible
from host.sim.targets import Target, central_target, load_target_list, staring_targets
from host.tune.pid_grid import GRIDS, grid
from host.tune.pid_tuning import AXES, TuningPlan, tune


def register(subparsers) -> None:
    p = subparsers.add_parser("tune", help="tune controllers on the batched simulator (Table 7 PID grid)",
                              description=__doc__.splitlines()[0])
    sub = p.add_subparsers(dest="tune_command", required=True, metavar="CONTROLLER")
    pid = sub.add_parser("pid", help="the Table 7 PID grid, each axis optimised on its share of eq. 8")
    pid.add_argument("--grid", default="coarse",
                     help=f"gain grid: {', '.join(sorted(GRIDS))} or kp=LO:HI:STEP,ki=...,kd=... (default coarse)")
    pid.add_argument("--targets", default="all", help="all (the 100), central, or N (the first N of the 100)")
    pid.add_argument("--duration", default="100", help="simulated seconds per run (default 100)")
    pid.add_argument("--seeds", default="0", help="noise seeds, comma separated (default 0)")
    pid.add_argument("--shard-size", default="60", help="gain triples per shard (default 60)")
    pid.add_argument("--config", default=None, metavar="FILE",
                     help="controller configuration to start from (default: `staregen config init`'s)")
    add_scenario_argument(pid)
    pid.add_argument("--scheduler", default=None, help="address of a running Dask scheduler (default: local cluster)")
    pid.add_argument("--workers", default=None, help="local cluster worker processes (default: all cores)")
    pid.add_argument("--no-progress", action="store_true", help="no progress bar")
    pid.add_argument("--out", required=True, help="tuning folder (created; reused when resuming)")
    pid.set_defaults(func=run_pid)


def parse_targets(text: str) -> tuple[tuple[str, float, float, int], ...]:
    """(name, lon, lat, noise stream): a target's stream is its index among the 100, as in
    `staregen simulate --target all`; the central target flies stream 0 as `--target central` does;
    a target list file (NAME,LON,LAT or LON,LAT per line, degrees) gives row i stream i."""
    if Path(text).is_file():
        return tuple((t.name, t.lon, t.lat, i) for i, t in enumerate(load_target_list(text)))
    key = text.strip().lower()
    if key == "central":
        c = central_target()
        return ((c.name, c.lon, c.lat, 0),)
    every = staring_targets()
    n = len(every) if key == "all" else parse_int(text, "--targets (all, central, a count or a file)", minimum=1,
                                                  maximum=len(every))
    return tuple((t.name, t.lon, t.lat, i) for i, t in enumerate(every[:n]))


def parse_seeds(text: str) -> tuple[int, ...]:
    parts = [p for p in text.split(",") if p.strip()]
    if not parts:
        raise HostError("--seeds needs at least one seed")
    seeds = tuple(parse_int(p.strip(), "--seeds", maximum=2**32 - 1) for p in parts)
    if len(set(seeds)) != len(seeds):
        raise HostError(f"--seeds lists a seed twice: {text}")
    return seeds


def run_pid(args: argparse.Namespace) -> int:
    scenario = load_scenario(args.scenario)
    plan = TuningPlan(grid=grid(args.grid), targets=parse_targets(args.targets), seeds=parse_seeds(args.seeds),
                      duration=parse_number(args.duration, "--duration", minimum=11.0, maximum=86400.0),
                      shard_size=parse_int(args.shard_size, "--shard-size", minimum=1, maximum=100_000),
                      errors=scenario.errors, scenario=scenario.describe())
    check_targets_visible([Target(n, lon, lat) for n, lon, lat, _ in plan.targets], plan.sim_config())
    base = pc.load(args.config) if args.config else default_package_config()
    workers = None if args.workers is None else parse_int(args.workers, "--workers", minimum=1, maximum=256)
    out = Path(args.out)
    print(f"tune pid: scenario {scenario.reading} (sha256 {scenario.sha256[:12]}), grid {plan.grid.name} ({len(plan.grid)} triples) x {len(plan.targets)} target(s) x "
          f"{len(plan.seeds)} seed(s), {plan.duration:g} s each, {plan.n_shards} shard(s)")
    doc = tune(out, plan, base, scheduler=args.scheduler, workers=workers, progress=not args.no_progress)
    t = doc["timing"]
    print(f"computed {t['shards_computed']} shard(s), kept {t['shards_kept']}; {t['scenarios_computed']} scenarios "
          f"in {t['compute_seconds']:.1f} s on {t['workers']} worker(s)"
          + (f" ({t['scenarios_per_second']:.1f} scenarios/s)" if t["scenarios_per_second"] else ""))
    print("axis     Kp      Ki      Kd   objective   (Table 1 on the grid: objective)")
    for name in AXES:
        b = doc["best"][name]
        t1 = f"{b['table1_objective']:.4e}" if b["table1_on_grid"] else "not on the grid"
        print(f"  {name}  {b['kp']:6g}  {b['ki']:6g}  {b['kd']:6g}   {b['objective']:.4e}   ({t1})")
    c = doc["check"]
    print(f"check run, J-bar over the targets: Table 1 {c['table1']['J']:.4e}, tuned {c['tuned']['J']:.4e} "
          f"(ratio {c['ratio_tuned_to_table1']:.3f})")
    print(f"tuned configuration: {out / 'controller.toml'}; result: {out / 'result.json'}")
    return 0
