"""Scalar vs batched simulator, side by side in one process (BENCHMARKS.md, issue 13):

    python -m host.tune.benchmark [--scalar-runs 3] [--gains 60] [--targets 100] [--duration 100]

Both fly the PID over `duration` s on the staring targets; the scalar simulator one run at a time
(host.sim.simulator.simulate), the batched one all (target, gain) scenarios at once. Reported: CPU
seconds and scenario-runs per CPU second of each, and the ratio. One process, one core: the
figure per core, which the Dask workers multiply.
"""
from __future__ import annotations

import argparse
import json
import time

import numpy as np

from host.control.pid import PidController, PidGains
from host.sim.batched import GainSets, simulate_pid_batch
from host.sim.simulator import SimConfig, simulate
from host.sim.targets import staring_targets
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


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--scalar-runs", type=int, default=3)
    p.add_argument("--gains", type=int, default=60)
    p.add_argument("--targets", type=int, default=100)
    p.add_argument("--duration", type=float, default=100.0)
    a = p.parse_args()
    print(json.dumps(measure(a.scalar_runs, a.gains, a.targets, a.duration), indent=2))


if __name__ == "__main__":
    main()
