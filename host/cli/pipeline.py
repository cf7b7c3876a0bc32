"""`staregen pipeline`: the whole flow on the default preset, as a sequence of stage functions.

For now: scenario summary, then the central-target PID simulation (metrics printed, artifacts in
<out>/pid_central/), then a short report. Later issues insert their stages (sample creation,
training, codegen, SIL/PIL) into STAGES. The output folder is built atomically: a failed stage
leaves no partial folder.
"""
from __future__ import annotations

import argparse
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from host.campaign import format_table, run_campaign, write_campaign
from host.constants import DEG
from host.earth import elevation
from host.errors import HostError
from host.metrics import DEFAULT_PLAN
from host.orbit import TABLE5_ELEMENTS, TABLE5_EPOCH_UTC
from host.simulator import SimConfig, environment_track
from host.targets import central_target
from tools import atomic

PRESET_DURATION_S = 100.0
PRESET_SEED = 0


@dataclass
class PipelineContext:
    out: Path                                     # the temporary folder being built
    results: dict = field(default_factory=dict)   # stage name -> summary (goes into report.json)
    report: list[str] = field(default_factory=list)


def stage_scenario(ctx: PipelineContext) -> None:
    """Epoch, orbit and the central target's elevation over the run (sanity of the geometry)."""
    cfg = SimConfig(duration=PRESET_DURATION_S)
    env = environment_track(cfg.control_steps * cfg.substeps + 1, cfg.plant_step)
    tg = central_target()
    el = elevation(env.R, env.jd_days, env.sec_of_day, tg.lon, tg.lat) / DEG
    e = TABLE5_ELEMENTS
    summary = {"epoch_utc": "%04d-%02d-%02d %02d:%02d:%06.3f" % TABLE5_EPOCH_UTC,
               "orbit": {"a_km": e.a / 1e3, "e": e.e, "inc_deg": e.inc / DEG, "raan_deg": e.raan / DEG,
                         "argp_deg": e.argp / DEG, "nu_deg": e.nu / DEG},
               "central_target_elevation_deg": {"start": float(el[0]), "max": float(np.max(el)),
                                                "end": float(el[-1])}}
    ctx.results["scenario"] = summary
    ctx.report.append(f"scenario: epoch {summary['epoch_utc']} UTC, central target elevation "
                      f"{el[0]:.1f}° -> max {np.max(el):.1f}° -> {el[-1]:.1f}° over {PRESET_DURATION_S:g} s")


def stage_pid_central(ctx: PipelineContext) -> None:
    """The paper's PID (Table 1) staring at the central target; metrics printed and saved."""
    result = run_campaign("pid", [central_target()], SimConfig(duration=PRESET_DURATION_S, seed=PRESET_SEED),
                          DEFAULT_PLAN, progress=False)
    write_campaign(result, ctx.out / "pid_central")
    a = result.average
    ctx.results["pid_central"] = {"J_A": a.J_A, "J_w": a.J_w, "J": a.J, "run_time_s": result.run_time_s}
    ctx.report.append(format_table(result))


def stage_report(ctx: PipelineContext) -> None:
    atomic.write_json(ctx.out / "report.json", ctx.results)
    atomic.write_text(ctx.out / "report.txt", "\n\n".join(ctx.report) + "\n")


STAGES = [stage_scenario, stage_pid_central, stage_report]


def register(subparsers) -> None:
    p = subparsers.add_parser("pipeline", help="run the whole flow on the default preset",
                              description=__doc__.splitlines()[0])
    p.add_argument("--out", default="out/pipeline", help="output folder (default out/pipeline)")
    p.set_defaults(func=main)


def main(args: argparse.Namespace) -> int:
    from host.cli.simulate import check_output_folder

    out = Path(args.out)
    check_output_folder(out, marker="report.json")
    start = time.perf_counter()
    try:
        with atomic.directory(out) as tmp:
            ctx = PipelineContext(out=tmp)
            for stage in STAGES:
                t0 = time.perf_counter()
                stage(ctx)
                print(f"[{stage.__name__.removeprefix('stage_')}] done in {time.perf_counter() - t0:.1f} s", flush=True)
    except OSError as exc:
        raise HostError(f"cannot write output folder {out}: {exc.strerror or exc}") from None
    print("\n\n".join(ctx.report))
    print(f"pipeline finished in {time.perf_counter() - start:.1f} s; artifacts in {out}")
    return 0
