"""`staregen samples`: optimal-control samples (paper 001 section 5) on Dask, sharded and resumable.

Draws N sample inputs S_in in the Table 2 box from --seed, solves one OCP per sample (host.learn.ocp)
on a local Dask cluster or an existing scheduler, and writes shards into --out (docs/ocp.md).
Rerunning the same command resumes: finished shards are validated and kept, the rest computed.
"""
from __future__ import annotations


from host.cli.args import parse_int, parse_number
from host.errors import HostError
from host.learn.ocp import OBJECTIVES, OcpConfig
from host.learn.samples import DEFAULT_SHARD_SIZE, DatasetPlan, create_dataset, load_dataset, timing_summary


def register(subparsers) -> None:
    p = subparsers.add_parser("samples", help="optimal-control samples for training, on Dask (resumable)",
                              description=__doc__.splitlines()[0])
    p.add_argument("--n", required=True, help="number of samples N (> 0)")
    p.add_argument("--objective", default="regularised", choices=OBJECTIVES,
                   help="OCP objective (default regularised; paper-l1 is eq. 6-8 literally)")
    p.add_argument("--scheduler", default=None,
                   help="existing Dask scheduler, tcp://host:port (default: a local cluster)")
    p.add_argument("--workers", default=None, help="local cluster worker processes (default: all cores)")
    p.add_argument("--seed", default="0", help="master seed (default 0)")
    p.add_argument("--shard-size", default=str(DEFAULT_SHARD_SIZE),
                   help=f"samples per shard (default {DEFAULT_SHARD_SIZE})")
    p.add_argument("--torque-bound", default=None,
                   help=f"torque bound per axis in N·m, or 'none' "
                        f"(default {OcpConfig().torque_bound:g}, the wheel limit)")
    defaults = OcpConfig()
    p.add_argument("--k1", default=None, help=f"OCP weight of the angle error (default {defaults.k1:g}, eq. 8)")
    p.add_argument("--k2", default=None, help=f"OCP weight of the rate error (default {defaults.k2:g}, eq. 8)")
    p.add_argument("--effort-weight", default=None,
                   help=f"regularised only: weight rho of (M - M_ff)^2 (default 1/289 = {defaults.effort_weight:.6g})")
    p.add_argument("--connect-timeout", default="10", help="seconds to reach --scheduler (default 10)")
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    p.add_argument("--out", required=True, help="dataset folder (created; reused when resuming)")
    p.set_defaults(func=main)


def _torque_bound(text: str | None) -> float | None:
    if text is None:
        return OcpConfig().torque_bound
    if text.lower() == "none":
        return None
    return parse_number(text, "--torque-bound", positive=True)


def _ocp_config(args) -> OcpConfig:
    """The OCP settings the flags change; the rest keep docs/ocp.md's defaults."""
    weights = {}
    for name, flag in (("k1", "--k1"), ("k2", "--k2"), ("effort_weight", "--effort-weight")):
        text = getattr(args, name)
        if text is not None:
            weights[name] = parse_number(text, flag, non_negative=True)
    if args.objective == "paper-l1" and "effort_weight" in weights:
        raise HostError("--effort-weight applies to the regularised objective only (paper-l1 has no effort term)")
    return OcpConfig(objective=args.objective, torque_bound=_torque_bound(args.torque_bound), **weights)


def main(args) -> int:
    n = parse_int(args.n, "--n (the number of samples)", 1)
    plan = DatasetPlan(
        n_samples=n,
        ocp=_ocp_config(args),
        master_seed=parse_int(args.seed, "--seed", 0),
        shard_size=parse_int(args.shard_size, "--shard-size", 1),
    ).validate()
    workers = None if args.workers is None else parse_int(args.workers, "--workers", 1)
    timeout = parse_number(args.connect_timeout, "--connect-timeout", positive=True)
    run = create_dataset(args.out, plan, scheduler=args.scheduler, workers=workers,
                         connect_timeout=timeout, progress=not args.no_progress)
    _, _, _, report = load_dataset(args.out)
    timing = timing_summary(args.out)
    print(f"dataset {run['directory']}: {report['n_total']} samples in {run['shards_total']} shards "
          f"({run['shards_kept']} finished shards kept, {run['shards_computed']} computed) "
          f"on {run['workers']} workers")
    print(f"objective {plan.ocp.objective}, config {plan.config_hash()[:12]}; usable for training "
          f"{report['n_used']}, excluded {report['n_excluded']} {report['excluded_by_status'] or ''}".rstrip())
    print(f"IPOPT iterations median {report['iterations_median']:g}, max {report['iterations_max']}; "
          f"solve time median {timing['solve_seconds_median'] * 1e3:.1f} ms wall, "
          f"{timing['solve_cpu_seconds_median'] * 1e3:.1f} ms cpu per sample; worker cpu with overheads "
          f"{timing['worker_cpu_seconds_per_sample'] * 1e3:.1f} ms/sample")
    print(f"this run: {run['samples_computed']} samples in {run['compute_seconds']:.1f} s of compute "
          f"({run['samples_per_second']:.1f} samples/s), {run['wall_seconds']:.1f} s wall with cluster start")
    return 0
