"""Issue 14 defect 4: every subcommand refuses bad input with exit 2, exactly one line on stderr,
no traceback and no new file. Placeholders: {net} a valid 12-40-3 artifact, {small} a valid 3-5-1
one, {file} an existing file, {dir} an existing folder, {x} a (5, 12) float32 .npy, {x0} a (0, 12)
one, {cfg} a valid controller.toml, {deep} an artifact nested 100000 deep."""
from __future__ import annotations

import json
import os

import numpy as np
import pytest

from codegen.artifact import random_artifact, sealed
from codegen.units.dp import tables as dp_tables
from codegen.units.dp.params import DpParams
from codegen.units.tanh.params import example_params
from host.learn.ocp import OcpConfig
from host.learn.samples import DatasetPlan, open_dataset_dir
from host.cli import build_parser, main
from host.control.nn_controller import CONFIG_SOURCES, default_package_config
from codegen.package import config as pc
from host.sim import scenario_file

CASES = [
    # argparse itself: one line, not the usage block
    ([], "the following arguments are required"),
    (["nonsense"], "invalid choice"),
    (["simulate", "--bogus"], "unrecognized arguments"),
    (["verify", "--target", "riscv"], "invalid choice"),
    (["cycles", "--mode", "fast"], "invalid choice"),
    (["samples"], "the following arguments are required: --n"),
    (["train"], "the following arguments are required"),
    (["artifact"], "the following arguments are required"),
    (["config"], "the following arguments are required"),
    (["package"], "the following arguments are required"),
    (["generate", "--config", "{cfg}"], "the following arguments are required"),
    # seeds and counts
    (["artifact", "random", "--seed", "-1", "--out", "{tmp}/a.json"], "--seed"),
    (["artifact", "random", "--seed", "x", "--out", "{tmp}/a.json"], "--seed"),
    (["verify", "--artifact", "{net}", "--seed", "-1"], "--seed"),
    (["verify", "--artifact", "{net}", "--vectors", "1e13"], "--vectors"),
    (["verify", "--artifact", "{net}", "--vectors", "10000000000000"], "--vectors"),
    (["verify", "--artifact", "{net}", "--vectors", "0"], "--vectors"),
    (["verify", "--unit", "controller", "--artifact", "{net}", "--sequences", "-2"], "--sequences"),
    (["verify", "--unit", "controller", "--artifact", "{net}", "--steps", "2"], "--steps"),
    (["tanh", "gate", "--params", "docs/tanh_paper000.toml", "--seed", "-1"], "--seed"),
    (["verify", "--unit", "tanh", "--params", "docs/tanh_paper000.toml", "--period", "1e-300"], "period"),
    (["verify", "--unit", "tanh", "--params", "docs/tanh_paper000.toml", "--period", "-1"], "--period"),
    (["verify", "--unit", "tanh", "--params", "docs/tanh_paper000.toml", "--period", "nan"], "--period"),
    (["verify", "--unit", "gp", "--params", "docs/gp_paper004.toml", "--period", "0.1"],
     "--period does not apply to unit gp"),
    (["verify", "--unit", "gp", "--params", "docs/rbf_paper002.toml"], "unknown key"),
    (["verify", "--unit", "gp"], "unit gp needs --params FILE"),
    (["cycles", "--artifact", "{net}", "--per-class", "0"], "--per-class"),
    (["cycles", "--artifact", "{net}", "--per-class", "1e9"], "--per-class"),
    (["cycles", "--artifact", "{net}", "--seed", "-5"], "--seed"),
    (["samples", "--n", "0", "--out", "{tmp}/s"], "--n"),
    (["samples", "--n", "-3", "--out", "{tmp}/s"], "--n"),
    (["samples", "--n", "1e15", "--out", "{tmp}/s"], "--n"),
    (["samples", "--n", "10", "--seed", "-1", "--out", "{tmp}/s"], "seed"),
    (["samples", "--n", "10", "--workers", "0", "--out", "{tmp}/s"], "--workers"),
    (["samples", "--n", "10", "--shard-size", "0", "--out", "{tmp}/s"], "shard"),
    (["samples", "--n", "10", "--torque-bound", "-1", "--out", "{tmp}/s"], "torque"),
    (["samples", "--n", "10", "--k2", "-5", "--out", "{tmp}/s"], "--k2 must not be negative"),
    (["dp", "accuracy", "--data", "{tmp}/none", "--r", "1.5"], "r must lie in (0, 1)"),
    (["dp", "accuracy", "--data", "{tmp}/none", "--r", "0"], "--r must be positive"),
    (["dp", "accuracy", "--data", "{tmp}/none", "--s-limit", "12"], "S_limit must be an integer in [13, 4096]"),
    (["dp", "accuracy", "--data", "{tmp}/none", "--s-limit", ","], "--s-limit needs at least one value"),
    (["dp", "accuracy", "--data", "{tmp}/none"], "none"),
    (["samples", "--n", "10", "--k1", "nan", "--out", "{tmp}/s"], "--k1 must be finite"),
    (["samples", "--n", "10", "--k1", "0", "--k2", "0", "--out", "{tmp}/s"], "must not both be 0"),
    (["samples", "--n", "10", "--objective", "paper-l1", "--effort-weight", "1", "--out", "{tmp}/s"],
     "regularised objective only"),
    (["train", "--data", "{tmp}/missing", "--out", "{tmp}/n.json"], "missing"),
    (["train", "--data", "{dir}", "--out", "{tmp}/n.json", "--epochs", "0"], "--epochs"),
    (["train", "--data", "{dir}", "--out", "{tmp}/n.json", "--hidden", "0"], "--hidden"),
    (["train", "--data", "{dir}", "--out", "{tmp}/n.json", "--seed", "-1"], "--seed"),
    # simulate
    (["simulate", "--duration", "1e12", "--out", "{tmp}/o"], "--duration"),
    (["simulate", "--duration", "-1", "--out", "{tmp}/o"], "--duration"),
    (["simulate", "--duration", "inf", "--out", "{tmp}/o"], "--duration"),
    (["simulate", "--seed", "-1", "--out", "{tmp}/o"], "seed"),
    (["simulate", "--controller", "tanh", "--period", "1e-300", "--out", "{tmp}/o"], "period"),
    (["simulate", "--controller", "tanh", "--dt", "0", "--out", "{tmp}/o"], "--dt"),
    (["simulate", "--controller", "nn", "--artifact", "{small}", "--out", "{tmp}/o"], "12-input"),
    (["simulate", "--controller", "nn-c", "--artifact", "{small}", "--out", "{tmp}/o"], "12-input"),
    (["simulate", "--controller", "nn", "--artifact", "{tmp}/none.json", "--out", "{tmp}/o"], "no such file"),
    (["simulate", "--target", "200,0", "--out", "{tmp}/o"], "below the horizon"),
    (["simulate", "--t-img", "0", "--out", "{tmp}/o"], "--t-img"),
    (["simulate", "--workers", "0", "--target", "all", "--out", "{tmp}/o"], "--workers"),
    (["simulate", "--out", "{file}"], "not a directory"),
    (["simulate", "--out", "/proc/staregen"], "output folder"),
    # impulse
    (["impulse", "--controller", "nn", "--artifact", "{small}", "--out", "{tmp}/o"], "12-input"),
    (["impulse", "--duration", "5", "--out", "{tmp}/o"], "--duration"),
    (["impulse", "--seed", "-1", "--out", "{tmp}/o"], "seed"),
    (["impulse", "--controller", "nope", "--out", "{tmp}/o"], "controller"),
    # artifacts
    (["artifact", "check", "{tmp}/none.json"], "no such file"),
    (["artifact", "check", "{deep}"], "nested deeper"),
    (["artifact", "check", "{dir}"], "cannot read"),
    (["artifact", "random", "--shape", "12-100000000-3", "--out", "{tmp}/a.json"], "--shape"),
    (["artifact", "random", "--shape", "12-0-3", "--out", "{tmp}/a.json"], "--shape"),
    (["artifact", "random", "--shape", "12-x-3", "--out", "{tmp}/a.json"], "--shape"),
    (["artifact", "random", "--out", "{dir}"], "directory"),
    (["artifact", "random", "--out", "{file}/a.json"], "File exists"),
    (["artifact", "random", "--out", "/proc/a.json"], "a.json"),
    # codegen / c-eval / cycles outputs
    (["codegen", "--artifact", "{net}", "--out", "{file}"], "not a directory"),
    (["codegen", "--artifact", "{net}", "--out", "/proc/staregen"], "--out"),
    (["codegen", "--artifact", "{net}", "--name", "Bad Name", "--out", "{tmp}/c"], "--name"),
    (["codegen", "--unit", "tanh", "--artifact", "{net}", "--out", "{tmp}/c"], "--artifact does not apply"),
    (["codegen", "--unit", "tanh", "--out", "{tmp}/c"], "--params"),
    (["codegen", "--unit", "tanh", "--params", "{file}", "--out", "{tmp}/c"], ".toml or .json"),
    (["tanh", "codegen", "--params", "docs/tanh_paper000.toml", "--out", "{file}"], "not a directory"),
    (["c-eval", "--artifact", "{net}", "--inputs", "{x}", "--out", "{dir}", "--target", "x86"], "directory"),
    (["c-eval", "--artifact", "{net}", "--inputs", "{x}", "--out", "{file}/y.npy", "--target", "x86"], "File exists"),
    (["c-eval", "--artifact", "{net}", "--inputs", "{x0}", "--out", "{tmp}/y.npy", "--target", "arm"], "no rows"),
    (["c-eval", "--artifact", "{net}", "--inputs", "{file}", "--out", "{tmp}/y.npy", "--target", "x86"], "inputs"),
    (["c-eval", "--artifact", "{small}", "--inputs", "{x}", "--out", "{tmp}/y.npy", "--target", "x86"], "(N, 3)"),
    (["cycles", "--artifact", "{net}", "--json", "{dir}"], "directory"),
    (["cycles", "--artifact", "{net}", "--json", "/proc/c.json"], "c.json"),
    (["cycles", "--unit", "controller", "--artifact", "{small}"], "12-input"),
    (["cycles", "--entry", "controller", "--artifact", "{small}"], "12-input"),
    (["verify", "--controller", "--artifact", "{small}"], "12-input"),
    (["verify", "--unit", "controller", "--artifact", "{small}"], "12-input"),
    # configuration and packages
    (["config", "init", "--out", "{dir}"], "exists"),
    (["config", "init", "--out", "{file}/c.toml"], "c.toml"),
    (["config", "init", "--name", "Bad", "--out", "{tmp}/c.toml"], "--name"),
    (["config", "check", "{tmp}/none.toml"], "cannot read"),
    (["config", "check", "{net}"], "not valid TOML"),
    (["config", "seal", "{file}"], "not valid TOML"),
    (["generate", "--config", "{cfg}", "--network", "{small}", "--out", "{tmp}/p"], "12-input"),
    (["generate", "--config", "{cfg}", "--network", "{net}", "--out", "{file}"], "not a directory"),
    (["generate", "--config", "{cfg}", "--network", "{net}", "--out", "{tmp}/p", "--vectors", "0"], "--vectors"),
    (["gp", "table1", "--sizes", "200,100", "--out", "{tmp}/g"], "--sizes must be increasing"),
    (["gp", "table1", "--sizes", "100", "--m", "150", "--out", "{tmp}/g"], "--m 150 is more than the smallest"),
    (["gp", "table1", "--sizes", "1_00", "--out", "{tmp}/g"], "--sizes must be an integer in ASCII digits"),
    (["gp", "table1", "--sizes", ",", "--out", "{tmp}/g"], "--sizes needs at least one value"),
    (["gp", "table1", "--repeats", "0", "--out", "{tmp}/g"], "--repeats must be at least 1"),
    (["gp", "table1", "--data", "real", "--out", "{tmp}/g"], "invalid choice"),
    (["gp", "table1", "--out", "{file}"], "not a directory"),
    (["basilisk"], "the following arguments are required: --package"),
    (["basilisk", "--package", "{tmp}/none", "--controller", "lqr", "--out", "{tmp}/b"], "unknown controller 'lqr'"),
    (["basilisk", "--package", "{tmp}/none", "--errors", "maybe", "--out", "{tmp}/b"], "invalid choice"),
    (["basilisk", "--package", "{file}", "--out", "{tmp}/b"], "no such folder"),
    (["simulate", "--controller", "rbf", "--params", "{tmp}/missing.toml", "--out", "{tmp}/s"], "missing.toml"),
    (["simulate", "--controller", "rbf", "--params", "docs/tanh_paper000.toml", "--out", "{tmp}/s"],
     "unknown key 'beta1'"),
    (["simulate", "--controller", "pid", "--params", "docs/rbf_paper002.toml", "--out", "{tmp}/s"],
     "--params applies to --controller rbf, rbf-c, rbf-arm, gp-baseline, gp, gp-c, gp-arm only"),
    (["simulate", "--controller", "rbf-c", "--target", "all", "--out", "{tmp}/s"], "--target and --scenario do not apply"),
    (["simulate", "--controller", "rbf", "--period", "0", "--out", "{tmp}/s"], "--period"),
    (["simulate", "--controller", "rbf", "--dt", "0.5", "--out", "{tmp}/s"], "--dt"),
    (["simulate", "--controller", "rbf-arm", "--duration", "1e9", "--out", "{tmp}/s"], "--duration"),
    # paper 004's takeover (gp-baseline, gp) and `gp train`
    (["simulate", "--controller", "gp", "--params", "{tmp}/missing.toml", "--out", "{tmp}/s"], "missing.toml"),
    (["simulate", "--controller", "gp", "--params", "docs/rbf_paper002.toml", "--out", "{tmp}/s"], "unknown key"),
    (["simulate", "--controller", "gp", "--period", "0.1", "--out", "{tmp}/s"], "--period does not apply"),
    (["simulate", "--controller", "gp-baseline", "--target", "all", "--out", "{tmp}/s"], "--target does not apply"),
    (["simulate", "--controller", "gp", "--duration", "0", "--out", "{tmp}/s"], "--duration"),
    (["simulate", "--controller", "gp", "--start", "far", "--out", "{tmp}/s"], "invalid choice"),
    (["simulate", "--controller", "gp", "--seed", "3", "--out", "{tmp}/s"], "--seed does not apply"),
    (["simulate", "--controller", "pid", "--start", "outside", "--out", "{tmp}/s"], "--start applies to"),
    (["simulate", "--controller", "rbf", "--start", "outside", "--out", "{tmp}/s"], "--start applies to"),
    (["gp", "train", "--m", "1", "--out", "{tmp}/g"], "--m must be at least 2"),
    (["gp", "train", "--iterations", "0", "--out", "{tmp}/g"], "--iterations must be at least 1"),
    (["gp", "train", "--seed", "x", "--out", "{tmp}/g"], "--seed"),
    (["gp", "train", "--out", "{file}"], "not a directory"),
    (["generate", "--config", "{cfg}", "--network", "{net}", "--params", "tanh", "--out", "{tmp}/p"],
     "--params: expected UNIT=FILE"),
    (["generate", "--config", "{cfg}", "--network", "{net}", "--params", "dp=x.toml", "--out", "{tmp}/p"],
     "--params: unknown unit 'dp'"),
    (["generate", "--config", "{cfg}", "--network", "{net}", "--params", "tanh=docs/tanh_paper000.toml",
      "--tanh", "docs/tanh_paper000.toml", "--out", "{tmp}/p"], "--params: unit tanh given twice"),
    (["generate", "--config", "{cfg}", "--network", "{net}", "--params", "tanh=docs/tanh_paper000.toml",
      "--out", "{tmp}/p"], "--params tanh=FILE given, but the configuration's [package] units do not include"),
    (["generate", "--config", "{cfg}", "--network", "{net}", "--out", "{tmp}/p", "--gate-vectors", "1e12"], "--gate-vectors"),
    (["generate", "--config", "{net}", "--network", "{net}", "--out", "{tmp}/p"], "not valid TOML"),
    (["package", "check", "{dir}"], "manifest.json"),
    (["package", "check", "{file}"], "not a directory"),
    # reports over units, the pipeline, the sweep, tuning
    (["fuzz", "--n", "0"], "--n"),
    (["fuzz", "--unit", "tanh", "--params", "{file}"], ".toml or .json"),
    (["coverage", "--vectors", "5"], "--vectors"),
    (["coverage", "--seed", "-1"], "--seed"),
    (["misra", "--params", "{file}"], ".toml or .json"),
    (["misra", "--unit", "bogus"], "invalid choice"),
    (["pipeline", "--out", "{file}"], "not a directory"),
    (["sweep", "--out", "{tmp}/s"], "--data"),
    (["tune"], "the following arguments are required"),
    (["tune", "pid", "--targets", "0", "--out", "{tmp}/t"], "--targets"),
    (["tune", "pid", "--seeds", "1,1", "--out", "{tmp}/t"], "twice"),
    (["tune", "pid", "--config", "{net}", "--out", "{tmp}/t"], "not valid TOML"),
    (["evaluate", "--network", "{small}", "--out", "{tmp}/e"], "12-input"),
    (["evaluate", "--network", "{net}", "--freqs", "7", "--out", "{tmp}/e"], "--freqs"),
    (["evaluate", "--network", "{net}", "--targets", "3", "--response-targets", "4", "--out", "{tmp}/e"],
     "--response-targets"),
    (["evaluate", "--network", "{net}", "--tuned", "{net}", "--out", "{tmp}/e"], "not valid TOML"),
    (["evaluate", "--network", "{net}", "--controllers", "pid,lqr", "--out", "{tmp}/e"], "unknown controller 'lqr'"),
    (["evaluate", "--network", "{net}", "--controllers", "nn-arm", "--out", "{tmp}/e"], "not available"),
    (["report", "--evaluate", "{tmp}/none", "--out", "{tmp}/r"], "not a folder"),
    (["report", "--evaluate", "{dir}", "--out", "{tmp}/r"], "evaluate.json"),
    (["report", "--evaluate", "{dir}", "--calibration", "{tmp}/none", "--out", "{tmp}/r"], "not a folder"),
    # scenario files (issue 24): wrong types, negative σ, unknown keys, NaN, a file that is not TOML
    (["evaluate", "--network", "{net}", "--scenario", "{scen_nan}", "--out", "{tmp}/e"], "must be finite"),
    (["evaluate", "--network", "{net}", "--scenario", "{scen_negative}", "--out", "{tmp}/e"], "must not be negative"),
    (["simulate", "--scenario", "{scen_unknown}", "--out", "{tmp}/o"], "unknown key"),
    (["simulate", "--scenario", "{scen_type}", "--out", "{tmp}/o"], "must be a number"),
    (["tune", "pid", "--scenario", "{net}", "--out", "{tmp}/t"], "TOML"),
    (["tune", "pid", "--scenario", "{tmp}/none.toml", "--out", "{tmp}/t"], "none.toml"),
    (["evaluate", "--network", "{net}", "--quick", "--engine", "warp", "--out", "{tmp}/e"], "invalid choice"),
    (["scenario", "check", "{scen_nan}"], "must be finite"),
    (["calibrate", "--network", "{small}", "--out", "{tmp}/c"], "12-input"),
    (["calibrate", "--network", "{net}", "--readings", "table7", "--out", "{tmp}/c"], "unknown reading"),
    (["calibrate", "--network", "{net}", "--scales", "-1", "--out", "{tmp}/c"], "--scales"),
    (["calibrate", "--network", "{net}", "--targets", "3", "--response-targets", "5", "--out", "{tmp}/c"],
     "--response-targets"),
    # issue 25 (data loss)
    (["generate", "--config", "{cfg}", "--network", "{net}", "--out", "{tmp}"], "lies inside output folder"),
    (["generate", "--config", "{cfg}", "--network", "{net}", "--out", "."], "is the current folder or holds it"),
    (["simulate", "--controller", "nn", "--artifact", "{net}", "--out", "{tmp}"], "lies inside output folder"),
    (["simulate", "--out", ".."], "is the current folder or holds it"),
    (["impulse", "--artifact", "{net}", "--out", "{tmp}"], "lies inside output folder"),
    (["pipeline", "--out", "."], "is the current folder or holds it"),
    (["tune", "pid", "--grid", "kp=17,ki=0,kd=46", "--targets", "1", "--duration", "11", "--out", "{tmp}"],
     "holds no tuning.json"),
    # issue 25 (CLI, tuning, report)
    (["report", "--evaluate", "{ev_lists}", "--out", "{tmp}/r"], "evaluate.json: not written by `staregen evaluate`: "
                                                                  "staring: must be an object"),
    (["report", "--evaluate", "{ev_row}", "--out", "{tmp}/r"], "staring['PID (Table 1)'].J_A: missing"),
    (["report", "--evaluate", "{ev_plan}", "--out", "{tmp}/r"], "plan.duration: must be a number > 0, got 'b'"),
    (["report", "--evaluate", "{ev_zero}", "--out", "{tmp}/r"], "staring['PID (Table 1)'].J: must be a number > 0"),
    (["report", "--evaluate", "{ev_good}", "--tune", "{tune_best}", "--out", "{tmp}/r"],
     "result.json: not written by `staregen tune pid`"),
    (["report", "--evaluate", "{ev_link}", "--out", "{tmp}/r"], "fig10_scatter.png: not embedded: not a regular file"),
    (["report", "--command", "staregen evaluate", "--evaluate", "{tmp}/none", "--out", "{tmp}/r"],
     "staregen report: error: --evaluate"),
    (["tune", "pid", "--targets", "central", "--out", "{tune_list}"],
     "tuning.json: unreadable tuning plan (expected a JSON object, got list)"),
    (["tune", "pid", "--grid", "kp=1.7e308,ki=0,kd=40", "--targets", "central", "--duration", "12", "--out", "{tmp}/t"],
     "--grid kp: a value the controller configuration cannot hold"),
    (["tune", "pid", "--grid", "kp=1_0,ki=0,kd=40", "--duration", "5", "--out", "{tmp}/t"], "grid kp=1_0"),
    (["tune", "pid", "--targets", "{targets_underscore}", "--duration", "5", "--out", "{tmp}/t"], ":1: unknown target"),
    (["simulate", "--target", "1_20,3_0", "--t-img", "0", "--out", "{tmp}/o"], "unknown target '1_20,3_0'"),
    (["generate", "--config", "{cfg}", "--network", "{net}", "--out", "{tmp}/p", "--gate-vectors", "1_00",
      "--vectors", "0"], "--gate-vectors must be an integer in ASCII digits"),
    (["verify", "--artifact", "{net}", "--vectors", " \u0664 ", "--steps", "2"],
     "--vectors must be an integer in ASCII digits"),
    (["artifact", "random", "--shape", "\u0661\u0662-40-3", "--out", "{tmp}/a.json"], "--shape"),
    (["dp", "build", "--data", "{tmp}/none", "--n-max", "1_000", "--out", "{tmp}/t.json"], "--n-max"),
    # issue 25 (integrity)
    (["generate", "--config", "{cfg}", "--network", "{net}", "--out", "{tmp}/p", "--sign-key", "{file}"],
     "a key needs at least 32 bytes"),
    (["generate", "--config", "{cfg}", "--network", "{net}", "--out", "{tmp}/p", "--sign-key", "{net}"],
     "larger than 1024 bytes"),
    (["generate", "--config", "{cfg}", "--network", "{net}", "--out", "{tmp}/p", "--sign-key", "{dir}"],
     "not a regular file"),
    (["generate", "--config", "{cfg}", "--network", "{net}", "--out", "{tmp}/p", "--sign-key", "{tmp}/none.key"],
     "cannot read the key"),
    (["package", "check", "{dir}", "--verify-key", "/dev/zero"], "not a regular file"),
    (["package", "check", "{dir}", "--verify-key", "{file}"], "a key needs at least 32 bytes"),
    (["package", "check", "{dir}", "--verify-key", "{tmp}/none.key"], "cannot read the key"),
    (["package", "check", "{dir}", "--run", "x86,qemu2"], "unknown target 'qemu2'"),
    # issue 25 (parameter files): ranges after float32 rounding, one name rule, no tracebacks,
    # capped reads of regular files, one number grammar; files from _issue25_parameter_files
    (["config", "check", "{tmp}/p25/torque_limit.toml"], "limits.torque_limit: 1e-50 rounds to 0 in float32"),
    (["config", "check", "{tmp}/p25/integral_limit.toml"], "pid.integral_limit: 1e-50 rounds to 0 in float32"),
    (["config", "check", "{tmp}/p25/control_period.toml"], "timing.control_period: 1e-50 rounds to 0 in float32"),
    (["config", "check", "{tmp}/p25/e2.toml"], "earth.e2: must be in [0, 1), got 0.9999999999999999 (as float32: 1.0)"),
    (["config", "check", "{tmp}/p25/name_sg.toml"], "package.name: must not be 'sg'"),
    (["config", "check", "{tmp}/p25/name_image.toml"], "package.name: must not be a CMake-reserved target"),
    (["generate", "--config", "{tmp}/p25/name_sg.toml", "--network", "{net}", "--out", "{tmp}/pkg"], "package.name"),
    (["codegen", "--unit", "controller", "--artifact", "{net}", "--name", "sg", "--out", "{tmp}/c"],
     "--name: must not be 'sg'"),
    (["config", "check", "{tmp}/p25/digits.toml"], "limits.torque_limit: must be finite (and within float32)"),
    (["config", "seal", "{tmp}/p25/digits.toml"], "limits.torque_limit: must be finite (and within float32)"),
    (["config", "check", "{tmp}/p25/underscore.toml"], "number '1_0.0': write plain decimal digits"),
    (["config", "check", "/dev/zero"], "/dev/zero: cannot read (not a regular file)"),
    (["config", "seal", "/dev/zero"], "/dev/zero: cannot read (not a regular file)"),
    (["artifact", "check", "/dev/zero"], "/dev/zero: file: cannot read (not a regular file)"),
    (["generate", "--config", "{cfg}", "--network", "{net}", "--tanh", "{tmp}/p25/zero.toml", "--out", "{tmp}/pkg"],
     "zero.toml: cannot read (not a regular file)"),
    (["artifact", "random", "--shape", "10000-10000-10000", "--out", "{tmp}/a.json"], "more than the 4,194,304 an artifact may hold"),
    (["tanh", "gate", "--params", "{tmp}/p25/eps1.toml"], "'eps1': 1e-50 rounds to 0 in float32"),
    (["tanh", "gate", "--params", "{tmp}/p25/eta.toml"], "'eta': 1e-300 rounds to 0 in float32"),
    (["tanh", "gate", "--params", "{tmp}/p25/gamma.json"], "'gamma': 1e-300 rounds to 0 in float32"),
    (["tanh", "gate", "--params", "{tmp}/p25/k1_digits.json"], "'k1': must be finite (and within float32)"),
    (["tanh", "gate", "--params", "{tmp}/p25/inertia_text.json"], "'inertia'[0][0]: must be a number, got '2_4.6'"),
    (["tanh", "gate", "--params", "{tmp}/p25/inertia_bool.json"], "'inertia'[0][1]: must be a number, got True"),
    (["tanh", "gate", "--params", "{tmp}/p25/duplicate.json"], "not valid JSON: duplicate key 'k1'"),
    (["verify", "--unit", "tanh", "--params", "{tmp}/p25/underscore_tanh.toml"], "number '1_5.0'"),
    (["codegen", "--unit", "dp", "--tables", "{tmp}/p25/dp_tukey.json", "--out", "{tmp}/c"],
     "tukey_c: 1e-300 rounds to 0 in float32"),
    (["dp", "build", "--data", "{tmp}/p25/ds_manifest", "--out", "{tmp}/t.json"],
     "dataset.json: unreadable dataset manifest (expected a JSON object, got list)"),
    (["dp", "build", "--data", "{tmp}/p25/ds_sidecar", "--out", "{tmp}/t.json"],
     "shard-00000.json: unreadable shard sidecar (expected a JSON object, got list)"),
]


def _bad_scenarios(folder) -> dict[str, str]:
    """Scenario files with one defect each (edited from a valid, sealed one: the value check comes first)."""
    good = scenario_file.to_toml(scenario_file.from_reading("table6"))
    edits = {"scen_nan": ("random_arcsec = [3.0, 3.0, 3.0]", "random_arcsec = [nan, 3.0, 3.0]"),
             "scen_negative": ("random_deg_per_h = [0.15, 0.15, 0.15]", "random_deg_per_h = [-0.15, 0.15, 0.15]"),
             "scen_unknown": ("[wheels]", "[wheels]\nspin = 1"),
             "scen_type": ("constant_Nm = [0.01, 0.01, 0.01]", "constant_Nm = [\"0.01\", 0.01, 0.01]")}
    out = {}
    for name, (old, new) in edits.items():
        assert old in good, old
        path = folder / f"{name}.toml"
        path.write_text(good.replace(old, new))
        out[name] = str(path)
    return out


def _issue25_files(folder) -> dict[str, str]:
    """Issue 25: report inputs with one defect each, a tuning folder whose plan is `[]`, a target row
    with underscores in its numbers."""
    row = {"J_A": 4e-4, "J_w": 8e-5, "J": 6e-4, "targets": 1}
    mean = {"overshoot_pct": [1, 2, 3], "settling_s": [4, 5, 6], "steady_state_deg": [0, 0, 0]}
    good = {"staring": {"PID (Table 1)": row}, "step": {"PID (Table 1)": {"mean": mean}},
            "frequency": {"PID (Table 1)": {"freqs_hz": [1.0], "amplitude_deg": [[1e-3]] * 3}},
            "plan": {"targets": 1, "duration": 12.0, "response_targets": 1, "freqs_hz": [1.0], "seed": 0}}
    docs = {"ev_good": good, "ev_lists": {"staring": [], "step": {}, "frequency": {}},
            "ev_row": {**good, "staring": {"PID (Table 1)": {}}},
            "ev_plan": {**good, "plan": {**good["plan"], "duration": "b"}},
            "ev_zero": {**good, "staring": {"PID (Table 1)": {**row, "J": 0}}}, "ev_link": good}
    out = {}
    for name, doc in docs.items():
        (folder / name).mkdir()
        (folder / name / "evaluate.json").write_text(json.dumps(doc))
        out[name] = str(folder / name)
    os.symlink("/etc/passwd", folder / "ev_link" / "fig10_scatter.png")
    for name, file, text in (("tune_best", "result.json", '{"best": 5}'), ("tune_list", "tuning.json", "[]")):
        (folder / name).mkdir()
        (folder / name / file).write_text(text)
        out[name] = str(folder / name)
    (folder / "targets_underscore.csv").write_text("a,1_20,3_0\n")
    return {**out, "targets_underscore": str(folder / "targets_underscore.csv")}


def _issue25_parameter_files(folder) -> None:
    """Issue 25: parameter files with one defect each, in folder/p25 (a valid file edited; the
    value checks come before the seal's)."""
    out = folder / "p25"
    out.mkdir()
    good = pc.to_toml(default_package_config())
    edits = {"torque_limit": ("torque_limit = 1.0", "torque_limit = 1e-50"),
             "integral_limit": ("integral_limit = 100.0", "integral_limit = 1e-50"),
             "control_period": ("control_period = 0.1", "control_period = 1e-50"),
             "e2": ("e2 = 0.0066943799901413165", "e2 = 0.9999999999999999"),
             "name_sg": ('name = "stare"', 'name = "sg"'), "name_image": ('name = "stare"', 'name = "image"'),
             "digits": ("torque_limit = 1.0", "torque_limit = " + "9" * 400),
             "underscore": ("torque_limit = 1.0", "torque_limit = 1_0.0")}
    for name, (old, new) in edits.items():
        assert old in good, old
        (out / f"{name}.toml").write_text(good.replace(old, new))
    (out / "zero.toml").symlink_to("/dev/zero")
    tanh = example_params().to_mapping()

    def tanh_file(name: str, text: str) -> None:
        (out / name).write_text(text)
    toml = "".join(f"{k} = {json.dumps(v)}\n" for k, v in tanh.items())
    tanh_file("eps1.toml", toml.replace("eps1 = 20.0", "eps1 = 1e-50"))
    tanh_file("eta.toml", toml.replace("eta = 0.002", "eta = 1e-300"))
    tanh_file("underscore_tanh.toml", toml.replace("k3 = 0.8", "k3 = 1_5.0"))
    tanh_file("gamma.json", json.dumps({**tanh, "gamma": 1e-300}))
    tanh_file("k1_digits.json", json.dumps({**tanh, "k1": 10 ** 400}))
    tanh_file("inertia_text.json", json.dumps({**tanh, "inertia": [["2_4.6", 0.1, 0.0], *tanh["inertia"][1:]]}))
    tanh_file("inertia_bool.json", json.dumps({**tanh, "inertia": [[3.0, True, 0.0], [True, 2.0, -0.2],
                                                                    [0.0, -0.2, 4.0]]}))
    tanh_file("duplicate.json", json.dumps(tanh)[:-1] + ', "k1": 2.0}')
    payload = json.loads(json.dumps(dp_tables.random_tables(60, DpParams(s_limit=32, n_min=20)).payload()))
    payload["params"]["tukey_c"] = 1e-300
    tanh_file("dp_tukey.json", json.dumps(sealed(dp_tables.FORMAT, dp_tables.VERSION, payload)))
    for name, broken in (("ds_manifest", "dataset.json"), ("ds_sidecar", "shard-00000.json")):
        open_dataset_dir(out / name, DatasetPlan(2, OcpConfig(), shard_size=2))
        (out / name / broken).write_text("[]")


@pytest.fixture()
def places(tmp_path, monkeypatch):
    monkeypatch.chdir(os.path.dirname(os.path.dirname(os.path.dirname(os.path.dirname(__file__)))))
    random_artifact((12, 40, 3), seed=1).save(tmp_path / "net.json")
    random_artifact((3, 5, 1), seed=1).save(tmp_path / "small.json")
    (tmp_path / "file.txt").write_text("just a file\n")
    (tmp_path / "folder").mkdir()
    np.save(tmp_path / "x.npy", np.zeros((5, 12), np.float32))
    np.save(tmp_path / "x0.npy", np.zeros((0, 12), np.float32))
    pc.write(default_package_config(), tmp_path / "controller.toml", CONFIG_SOURCES)
    (tmp_path / "deep.json").write_text("[" * 100_000 + "]" * 100_000)
    _issue25_parameter_files(tmp_path)
    return {**_bad_scenarios(tmp_path), **_issue25_files(tmp_path), "tmp": str(tmp_path),
            "net": str(tmp_path / "net.json"), "small": str(tmp_path / "small.json"),
            "file": str(tmp_path / "file.txt"), "dir": str(tmp_path / "folder"), "x": str(tmp_path / "x.npy"),
            "x0": str(tmp_path / "x0.npy"), "cfg": str(tmp_path / "controller.toml"), "deep": str(tmp_path / "deep.json")}


def snapshot(root: str) -> set[str]:
    return {os.path.join(d, f) for d, dirs, files in os.walk(root) for f in files + dirs}


def test_there_are_enough_cases():
    assert len(CASES) >= 80
    commands = set(build_parser()._subparsers._group_actions[0].choices)   # every registered subcommand
    assert {argv[0] for argv, _ in CASES if argv} - {"nonsense"} == commands


@pytest.mark.parametrize("argv, message", CASES, ids=[" ".join(a)[:60] or "(none)" for a, _ in CASES])
def test_bad_input_is_one_line_exit_2_no_file(places, capsys, argv, message):
    argv = [a.format(**places) for a in argv]
    before = snapshot(places["tmp"])
    code = main(argv)
    out, err = capsys.readouterr()
    assert code == 2, (code, err)
    assert err.count("\n") == 1 and "Traceback" not in err, err
    assert message in err, err
    assert snapshot(places["tmp"]) == before

