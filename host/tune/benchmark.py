"""Scalar vs batched simulator, side by side in one process (BENCHMARKS.md, issue 13):

    python -m host.tune.benchmark [--scalar-runs 3] [--gains 60] [--targets 100] [--duration 100]

Both fly the PID over `duration` s on the staring targets; the scalar simulator one run at a time
(host.sim.simulator.simulate), the batched one all (target, gain) scenarios at once. Reported: CPU
seconds and scenario-runs per CPU second of each, and the ratio. One process, one core: the
figure per core, which the Dask workers multiply.

    python -m host.tune.benchmark --evaluate NETWORK [--tuned T] [--dp-tables D] [--targets N]

The whole paper-scale evaluation (`staregen evaluate --sil`: staring, step over the targets,
frequency; the impulse is the same single scalar run in both) through both engines in one run, the
batched one first: wall seconds of each, per experiment, and the largest relative difference of J
over every staring row (issue 24).
"""
from __future__ import annotations

import argparse
import json
import time

import numpy as np

from codegen.package import config as pc
from host.control.pid import PidController, PidGains
from host.learn.training import baselines_path
from host.sim.batched import GainSets, simulate_pid_batch
from host.sim.simulator import SimConfig, simulate
from host.sim.targets import central_target, staring_targets
from host.tune.evaluate import ControllerSpec, EvalPlan, evaluate, table1_spec, tuned_spec
from host.tune.pid_grid import GRIDS
from host.tune.pid_tuning import same_triple_on_every_axis


def measure(scalar_runs: int, gains: int, targets: int, duration: float) -> dict:
    cfg = SimConfig(duration=duration)
    tg = staring_targets()[:targets]
    triples = GRIDS["table7"].triples(0, gains)
    simulate(PidController(), tg[0].lon, tg[0].lat, SimConfig(duration=11.0))   # warm the caches
    t0 = time.process_time()
    for i in range(scalar_runs):
        k = triples[i % gains]
        simulate(PidController(PidGains(np.full(3, k[0]), np.full(3, k[1]), np.full(3, k[2]))),
                 tg[i % targets].lon, tg[i % targets].lat, cfg, stream=i % targets)
    scalar = time.process_time() - t0
    t0 = time.process_time()
    simulate_pid_batch([(t.lon, t.lat) for t in tg], same_triple_on_every_axis(triples), (0,), cfg)
    batched = time.process_time() - t0
    s_rate, b_rate = scalar_runs / scalar, gains * targets / batched
    return {"duration_s": duration, "scalar_runs": scalar_runs, "scalar_cpu_s": round(scalar, 2),
            "scalar_runs_per_cpu_s": round(s_rate, 3), "batched_scenarios": gains * targets,
            "batched_cpu_s": round(batched, 2), "batched_runs_per_cpu_s": round(b_rate, 1),
            "ratio": round(b_rate / s_rate, 1)}


def evaluation_specs(network: str, tuned: str | None, dp_tables: str | None) -> list[ControllerSpec]:
    specs = [table1_spec()]
    if tuned:
        g = pc.load(tuned).controller
        specs.append(tuned_spec(g.kp, g.ki, g.kd))
    specs += [ControllerSpec("NN (float64)", "nn", (("artifact", network),)),
              ControllerSpec("NN (SIL, x86 C)", "nn-c", (("artifact", network),))]
    laws = baselines_path(network)
    if laws.exists():
        specs.append(ControllerSpec("PD+FF", "pdff", (("baselines", str(laws)),)))
    if dp_tables:
        specs += [ControllerSpec("DP (float64)", "dp", (("tables", dp_tables),)),
                  ControllerSpec("DP (SIL, x86 C)", "dp-c", (("tables", dp_tables),))]
    return specs


def measure_evaluation(network: str, tuned: str | None, dp_tables: str | None, targets: int) -> dict:
    every = staring_targets()[:targets]
    rows = tuple((t.name, t.lon, t.lat, i) for i, t in enumerate(every))
    c = central_target()
    specs = evaluation_specs(network, tuned, dp_tables)
    out = {"targets": targets, "controllers": [s.label for s in specs]}
    results = {}
    for engine in ("batched", "scalar"):
        plan = EvalPlan(targets=rows, response_targets=rows, central=(c.name, c.lon, c.lat, 0), engine=engine)
        t0 = time.perf_counter()
        results[engine] = evaluate(plan, specs, progress=False)
        out[f"{engine}_wall_s"] = round(time.perf_counter() - t0, 1)
        out[f"{engine}_experiments_s"] = results[engine]["timing"]
    diffs = [abs(results["batched"][t][k]["J"] / results["scalar"][t][k]["J"] - 1.0)
             for t in ("staring", "staring_central") for k in results["scalar"][t]]
    out["max_relative_difference_J"] = max(diffs)
    out["speed_up"] = round(out["scalar_wall_s"] / out["batched_wall_s"], 1)
    return out


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--scalar-runs", type=int, default=3)
    p.add_argument("--gains", type=int, default=60)
    p.add_argument("--targets", type=int, default=100)
    p.add_argument("--duration", type=float, default=100.0)
    p.add_argument("--evaluate", default=None, metavar="NETWORK", help="compare the engines on a whole evaluation")
    p.add_argument("--tuned", default=None)
    p.add_argument("--dp-tables", default=None)
    a = p.parse_args()
    if a.evaluate:
        print(json.dumps(measure_evaluation(a.evaluate, a.tuned, a.dp_tables, a.targets), indent=2))
        return
    print(json.dumps(measure(a.scalar_runs, a.gains, a.targets, a.duration), indent=2))


if __name__ == "__main__":
    main()
