"""`staregen pipeline`: the whole flow on the default preset, as a sequence of stage functions.

Stages: scenario summary; the central-target PID simulation (<out>/pid_central/); optimal-control
samples on Dask (<out>/samples/, the `regularised` objective); training of the 12-40-3 tansig
network on them (<out>/network.json, <out>/training.md); the generated C (<out>/c/); the three-way bit-exact gate (golden == x86 ==
ARM); the Cortex-M4 cycle summary in the three memory modes (<out>/cycles.json, cycles.md); the
flight package of the whole Fig. 2 controller with the default configuration (<out>/package,
<out>/controller.toml); small presets of PID tuning (<out>/tune), the discrete-point tables of paper 003
(<out>/dp_tables.json), evaluation (<out>/evaluate, the discrete-point law among the controllers) and
their report (<out>/report/report.md, report.html); a summary (report.json, report.txt). The output folder is built atomically: a failed stage leaves
no partial folder.
"""
from __future__ import annotations

import argparse
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from host.sim.campaign import format_table, run_campaign, write_campaign
from host.core.constants import DEG
from host.plant.earth import elevation
from host.errors import HostError
from host.outputs import check_output_folder, json_marker_owner
from host.sim import scenario_file
from host.sim.metrics import DEFAULT_PLAN
from host.plant.orbit import TABLE5_ELEMENTS, TABLE5_EPOCH_UTC
from host.sim.simulator import SimConfig, environment_track
from host.sim.targets import central_target
from codegen import atomic
from codegen.cgen import write_sources
from codegen.units.network.unit import NetworkUnit
from host.cli.generate import file_sha256, generate, summary
from host.control.nn_controller import CONFIG_SOURCES, default_package_config
from codegen.package import config as pc
from tools.package import EvidencePlan
from host.cli.verify import TARGETS
from tools.gate import run_gate
from tools.m4.profile import MODES
from tools.report import cycle_report, cycle_text

PRESET_DURATION_S = 100.0
PRESET_SEED = 0


@dataclass
class PipelineContext:
    out: Path                                     # the temporary folder being built
    final: Path = Path()                          # where it lands
    results: dict = field(default_factory=dict)   # stage name -> summary (goes into report.json)
    artifact: object = None                       # the network artifact (codegen.artifact.Artifact)
    unit: object = None                           # the network unit generated from it
    report: list[str] = field(default_factory=list)
    # the reading of Table 6 every stage flies (the commands' default: the calibration study's)
    scenario: scenario_file.Scenario = field(default_factory=scenario_file.default_scenario)


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
    summary["errors"] = ctx.scenario.describe()
    ctx.results["scenario"] = summary
    ctx.report.append(f"scenario: Table 6 errors read as {ctx.scenario.reading} (sha256 {ctx.scenario.sha256[:16]}…); "
                      f"epoch {summary['epoch_utc']} UTC, central target elevation "
                      f"{el[0]:.1f}° -> max {np.max(el):.1f}° -> {el[-1]:.1f}° over {PRESET_DURATION_S:g} s")


def stage_pid_central(ctx: PipelineContext) -> None:
    """The paper's PID (Table 1) staring at the central target; metrics printed and saved."""
    result = run_campaign("pid", [central_target()], SimConfig(duration=PRESET_DURATION_S, seed=PRESET_SEED,
                                                             errors=ctx.scenario.errors),
                          DEFAULT_PLAN, progress=False)
    write_campaign(result, ctx.out / "pid_central", ctx.scenario.describe())
    a = result.average
    ctx.results["pid_central"] = {"J_A": a.J_A, "J_w": a.J_w, "J": a.J, "run_time_s": result.run_time_s}
    ctx.report.append(format_table(result))


GATE_VECTORS = 100_000
GATE_SEED = 0
CYCLES_PER_CLASS = 100


PRESET_SAMPLES = 2_000


def stage_samples(ctx: PipelineContext) -> None:
    """Optimal-control samples (CasADi/IPOPT) on a Dask LocalCluster, sharded as `staregen samples`."""
    from host.learn.ocp import OcpConfig
    from host.learn.samples import DatasetPlan, create_dataset, load_dataset

    plan = DatasetPlan(n_samples=PRESET_SAMPLES, ocp=OcpConfig(), master_seed=PRESET_SEED).validate()
    run = create_dataset(ctx.out / "samples", plan, progress=True)
    _, _, _, report = load_dataset(ctx.out / "samples")
    ctx.results["samples"] = {"n": report["n_total"], "used": report["n_used"], "objective": plan.ocp.objective,
                              "samples_per_second": run["samples_per_second"], "workers": run["workers"]}
    ctx.report.append(f"samples: {report['n_total']} ({plan.ocp.objective}), {report['n_used']} usable, "
                      f"{run['samples_per_second']:.1f} samples/s on {run['workers']} workers")


def stage_train(ctx: PipelineContext) -> None:
    """The 12-40-3 tansig network trained on the samples; its artifact feeds codegen."""
    from host.learn import training

    a, report = training.train_artifact(ctx.out / "samples", recipe="default", seed=PRESET_SEED)
    training.save_artifact(a, ctx.out / "network.json")
    training.save_baselines(report, ctx.out / "network.json")
    atomic.write_text(ctx.out / "training.md", report.summary() + "\n")
    ctx.artifact = a
    ctx.results["network"] = {"artifact": "network.json", "shape": a.shape_text, "sha256": a.sha256,
                              "relative_torque_error": report.net.get("relative_torque_error"),
                              "train_seconds": round(report.train_seconds, 2)}
    ctx.report.append(report.summary())


def stage_codegen(ctx: PipelineContext) -> None:
    """Flight C of the network path into <out>/c (network.h/.c, sg_math.h/.c)."""
    ctx.unit = NetworkUnit(ctx.artifact)
    files = write_sources(ctx.unit.sources(), ctx.out / "c")
    ctx.results["codegen"] = {"folder": "c", "files": sorted(Path(f).name for f in files)}
    ctx.report.append("codegen: " + ", ".join(sorted(Path(f).name for f in files)) + " in c/")


def stage_gate(ctx: PipelineContext) -> None:
    """golden == x86 C == ARM C, bit for bit, on the gate's vector set (SPEC section 6)."""
    result = run_gate(ctx.unit, GATE_VECTORS, 0, 0, GATE_SEED, TARGETS)
    ctx.results["gate"] = {"vectors": GATE_VECTORS, "targets": ["golden", *TARGETS], "pass": result.ok,
                           "time_s": result.seconds["total"]}
    if not result.ok:
        raise HostError("bit-exact gate failed: golden, x86 and ARM outputs differ (see above)")
    ctx.report.append(f"gate: golden == x86 == ARM on {GATE_VECTORS} vectors "
                      f"({ctx.results['gate']['time_s']} s)")


def stage_cycles(ctx: PipelineContext) -> None:
    """Cortex-M4 cycles, flash, RAM and stack of the network path (cycle model, all modes)."""
    entry = cycle_report(ctx.unit, MODES, CYCLES_PER_CLASS, GATE_SEED)
    lines = cycle_text(entry)
    atomic.write_json(ctx.out / "cycles.json", {"entries": {"network": entry}})
    atomic.write_text(ctx.out / "cycles.md", "# Cycle report (pipeline)\n\n" + "\n".join(lines) + "\n")
    worst = {m: entry["cycles"][m]["max"] for m in MODES}
    ctx.results["cycles"] = {"network_max": worst, "flash_bytes": entry["flash_bytes"],
                             "ram_bytes": entry["ram_bytes"], "stack_bytes": entry["stack_bytes"]}
    ctx.report.append("cycles (network path, worst case): " + ", ".join(f"{m} {c}" for m, c in worst.items())
                      + f"; flash {entry['flash_bytes']} B, RAM {entry['ram_bytes']} B, stack {entry['stack_bytes']} B"
                      + " (paper: 3.3 ms = 554,400 cycles)")


def stage_package(ctx: PipelineContext) -> None:
    """The flight package of the trained network with the default configuration (<out>/package,
    its configuration in <out>/controller.toml): sources, self-test, CMakeLists, ICD, manifest."""
    cfg = default_package_config()
    config_file = pc.write(cfg, ctx.out / "controller.toml", CONFIG_SOURCES)
    network_file = ctx.out / "network.json"
    inputs = {"config": {"file": "controller.toml", "sha256": file_sha256(config_file), "values_sha256": cfg.sha256},
              "network": {"file": "network.json", "sha256": file_sha256(network_file),
                          "payload_sha256": ctx.artifact.sha256, "shape": ctx.artifact.shape_text}}
    result = generate(cfg, ctx.artifact, ctx.out / "package", inputs, plan=PACKAGE_PLAN)
    ev = result.manifest["evidence"]
    step = ev["units"]["controller"]["cycles"]["step"]
    ctx.results["package"] = {"folder": "package", "name": cfg.name, "files": len(result.manifest["files"]) + 1,
                              "selftest_mismatches": {t: r["selftest_mismatches"] for t, r in ev["package_build"].items()},
                              "step_max_cycles": {m: step[m]["max"] for m in MODES}, "seconds": result.seconds}
    lines = summary(result)
    lines[0] = lines[0].replace(str(ctx.out), str(ctx.final))
    ctx.report.append("\n".join(lines))


# A small preset of `staregen tune pid` (the Table 7 grid at paper scale is a benchmark); the
# evaluation flies at paper scale: 100 targets × 100 s, the step response over the 100.
TUNE_TARGETS, TUNE_DURATION_S = 4, 20.0


def stage_tune(ctx: PipelineContext) -> None:
    """The coarse PID grid over the first targets on the batched simulator (<out>/tune)."""
    from host.cli.tune import parse_targets
    from host.tune.pid_grid import grid
    from host.tune.pid_tuning import TuningPlan, tune

    plan = TuningPlan(grid=grid("coarse"), targets=parse_targets(str(TUNE_TARGETS)), duration=TUNE_DURATION_S,
                      errors=ctx.scenario.errors, scenario=ctx.scenario.describe())
    doc = tune(ctx.out / "tune", plan, default_package_config(), progress=False)
    best = {a: [doc["best"][a][k] for k in ("kp", "ki", "kd")] for a in doc["best"]}
    ctx.results["tune"] = {"folder": "tune", "grid": "coarse", "best_kp_ki_kd": best, "check": doc["check"]}
    ctx.report.append(f"tune pid (coarse grid, {TUNE_TARGETS} targets, {TUNE_DURATION_S:g} s): best (Kp, Ki, Kd) "
                      f"x {best['x']}, y {best['y']}, z {best['z']}; check run J-bar Table 1 "
                      f"{doc['check']['table1']['J']:.3e}, tuned {doc['check']['tuned']['J']:.3e}")


def stage_dp(ctx: PipelineContext) -> None:
    """The discrete-point controller's tables (paper 003) from the training split of the samples
    (<out>/dp_tables.json), default settings; it flies in the evaluation next."""
    from codegen.units.dp import tables as dp_tables
    from codegen.units.dp.params import DpParams
    from host.learn import training

    X, Y, _ = training.load_training_data(ctx.out / "samples")
    split = training.make_split(X, Y, PRESET_SEED)
    t = dp_tables.from_arrays(split.X_train, split.Y_train, DpParams(), {
        "creator": "staregen pipeline", "seed": PRESET_SEED, "dataset_sha256": training.dataset_sha256(X, Y)})
    t.save(ctx.out / "dp_tables.json")
    ctx.results["dp"] = {"tables": "dp_tables.json", "samples": t.n, "flash_bytes": t.flash_bytes,
                         "levels": t.n_levels, "sha256": t.sha256}
    ctx.report.append(f"discrete point (paper 003): {t.n} anchor samples, {t.flash_bytes:,} bytes of flash, "
                      f"{t.n_levels} box levels -> {ctx.final / 'dp_tables.json'}")


def stage_evaluate(ctx: PipelineContext) -> None:
    """NN (float64, SIL, PIL on the central target), Table 1 and tuned PID, PD+FF, the discrete-point
    law (float64, SIL): staring, step, frequency and impulse responses at paper scale on the batched
    simulator, under the pipeline's scenario (the commands' default reading) (<out>/evaluate), then the report
    (<out>/report)."""
    from host.cli.evaluate import summary
    from host.cli.tune import parse_targets
    from host.tune import figures
    from host.tune.evaluate import ControllerSpec, EvalPlan, evaluate, table1_spec, tuned_spec
    from host.tune.report import write_report

    targets = parse_targets("all")
    c = central_target()
    scenario = ctx.scenario
    plan = EvalPlan(targets=targets, response_targets=targets, central=(c.name, c.lon, c.lat, 0),
                    duration=PRESET_DURATION_S, errors=scenario.errors)
    tuned = pc.load(ctx.out / "tune" / "controller.toml").controller
    net, laws = str(ctx.out / "network.json"), str(ctx.out / "network.baselines.json")
    specs = [table1_spec(), tuned_spec(tuned.kp, tuned.ki, tuned.kd),
             ControllerSpec("NN (float64)", "nn", (("artifact", net),)),
             ControllerSpec("NN (SIL, x86 C)", "nn-c", (("artifact", net),)),
             ControllerSpec("NN (PIL, ARM, central)", "nn-arm", (("artifact", net),)),
             ControllerSpec("PD+FF", "pdff", (("baselines", laws),)),
             ControllerSpec("DP (float64)", "dp", (("tables", str(ctx.out / "dp_tables.json")),)),
             ControllerSpec("DP (SIL, x86 C)", "dp-c", (("tables", str(ctx.out / "dp_tables.json")),))]
    folder = ctx.out / "evaluate"
    result = evaluate(plan, specs, progress=False)
    result["scenario"] = scenario.describe()
    result = figures.write_evaluation(result, net, PRESET_SEED, folder, scenario.errors)
    write_report(ctx.out / "report", folder, ctx.out / "tune", ["staregen pipeline (tune pid on a small preset; "
                                                               "evaluate at paper scale)"])
    ctx.results["evaluate"] = {"folder": "evaluate", "report": "report/report.html",
                               "staring": {k: {m: v[m] for m in ("J_A", "J_w", "J", "targets")}
                                           for k, v in result["staring"].items()}}
    ctx.report.append(f"evaluate ({len(targets)} targets, {PRESET_DURATION_S:g} s, scenario {scenario.reading}; report in "
                      f"{ctx.final / 'report' / 'report.html'}):\n" + summary(result))


def stage_report(ctx: PipelineContext) -> None:
    atomic.write_json(ctx.out / "report.json", ctx.results)
    atomic.write_text(ctx.out / "report.txt", "\n\n".join(ctx.report) + "\n")


STAGES = [stage_scenario, stage_pid_central, stage_samples, stage_train, stage_codegen, stage_gate, stage_cycles,
          stage_package, stage_tune, stage_dp, stage_evaluate, stage_report]
# The package's evidence at pipeline scale (the standalone `staregen generate` defaults measure more).
PACKAGE_PLAN = EvidencePlan(gate_vectors=20_000, gate_sequences=4, sequence_steps=200, selftest_vectors=256,
                            cycles_per_class=20, seed=PRESET_SEED)


def register(subparsers) -> None:
    p = subparsers.add_parser("pipeline", help="run the whole flow on the default preset",
                              description=__doc__.splitlines()[0])
    p.add_argument("--out", default="out/pipeline", help="output folder (default out/pipeline)")
    p.set_defaults(func=main)


def main(args: argparse.Namespace) -> int:
    out = Path(args.out)
    check_output_folder(out, json_marker_owner("report.json"))
    start = time.perf_counter()
    try:
        with atomic.directory(out) as tmp:
            ctx = PipelineContext(out=tmp, final=out)
            for stage in STAGES:
                t0 = time.perf_counter()
                stage(ctx)
                print(f"[{stage.__name__.removeprefix('stage_')}] done in {time.perf_counter() - t0:.1f} s", flush=True)
    except OSError as exc:
        raise HostError(f"cannot write output folder {out}: {exc.strerror or exc}") from None
    print("\n\n".join(ctx.report))
    print(f"pipeline finished in {time.perf_counter() - start:.1f} s; artifacts in {out}")
    return 0
