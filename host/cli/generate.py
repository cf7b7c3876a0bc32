"""`staregen generate --config controller.toml --network network.json [--params UNIT=FILE ...] --out DIR`:
the flight package (sources, self-test, CMakeLists, ICD, manifest with the evidence).

The configuration and the network (and the parameter file of every other unit the configuration
includes: `--params tanh=docs/tanh_paper000.toml`, `--params rbf=docs/rbf_paper002.toml`) are
validated before anything is generated; the package folder appears only when
complete, and only when the gate and the self-test on x86 and ARM found no mismatch.
"""
from __future__ import annotations

import argparse
import dataclasses
import hashlib
from pathlib import Path

from codegen import artifact as art
from codegen import reading
from codegen import units as unit_registry
from codegen.package import config as pc
from codegen.package.manifest import load_key
from codegen.package.selftest import MAX_VECTORS
from host.cli.args import parse_int
from host.errors import HostError
from host.outputs import check_output_folder, package_owner
from host.sim.scenarios import package_units
from tools.package import EvidencePlan, build_package
from tools.m4.profile import MODES


def register(subparsers) -> None:
    p = subparsers.add_parser("generate", help="write the flight package (sources, self-test, ICD, manifest)",
                              description=__doc__.splitlines()[0])
    p.add_argument("--config", required=True, metavar="FILE", help="controller configuration (staregen config init)")
    p.add_argument("--network", required=True, metavar="FILE", help="network artifact (e.g. out/pipeline/network.json)")
    p.add_argument("--params", action="append", default=[], metavar="UNIT=FILE",
                   help="parameter file of a unit the configuration includes besides the controller (repeat per unit; "
                   f"units: {', '.join(pc.known_units()[1:])})")
    p.add_argument("--tanh", default=None, metavar="FILE", help="shorthand for --params tanh=FILE")
    p.add_argument("--out", required=True, metavar="DIR", help="package folder (new or empty, or replaced if it holds "
                   "exactly a staregen package)")
    p.add_argument("--pid-only", action="store_true",
                   help="emit the controller's network envelope empty: every step flies the PID fallback (a PID-only "
                        "package: the paper's PID alone, e.g. `staregen basilisk --controller pid`)")
    p.add_argument("--sign-key", default=None, metavar="FILE", help="key file (at least 32 random bytes, kept by "
                   "you): sign the manifest with HMAC-SHA256 (`package check --verify-key FILE`)")
    add_evidence_arguments(p)
    p.set_defaults(func=run)


def add_evidence_arguments(p: argparse.ArgumentParser) -> None:
    d = EvidencePlan()
    p.add_argument("--vectors", default=str(d.selftest_vectors), metavar="N",
                   help=f"self-test vectors per unit (default {d.selftest_vectors})")
    p.add_argument("--gate-vectors", default=str(d.gate_vectors), metavar="N",
                   help=f"gate vectors per unit measured into the manifest (default {d.gate_vectors})")
    p.add_argument("--cycles-per-class", default=str(d.cycles_per_class), metavar="N",
                   help=f"cycle-model vectors per class (default {d.cycles_per_class})")
    p.add_argument("--seed", default=str(d.seed), help=f"vector seed (default {d.seed})")


def evidence_plan(args: argparse.Namespace) -> EvidencePlan:
    return EvidencePlan(gate_vectors=parse_int(args.gate_vectors, "--gate-vectors", minimum=100, maximum=10_000_000),
                        selftest_vectors=parse_int(args.vectors, "--vectors", minimum=1, maximum=MAX_VECTORS),
                        cycles_per_class=parse_int(args.cycles_per_class, "--cycles-per-class", minimum=1,
                                                   maximum=10_000),
                        seed=parse_int(args.seed, "--seed", maximum=2**63 - 1))


def file_sha256(path: Path) -> str:
    try:
        return hashlib.sha256(reading.read_bytes(path)).hexdigest()
    except reading.InputFileError as exc:
        raise HostError(str(exc)) from None


def generate(cfg: pc.PackageConfig, network: art.Artifact, out: Path, inputs: dict, params: dict | None = None,
             plan: EvidencePlan = EvidencePlan(), log=print, input_paths=(), sign_key: bytes | None = None,
             units: dict | None = None):
    """The package of a validated configuration and network (also the pipeline's last stage);
    `params`: {unit: its parameters}, or `units` already bound by package_units; `input_paths`: the
    files read, which must not lie in the folder it replaces."""
    check_output_folder(out, package_owner, input_paths)
    units = units if units is not None else package_units(cfg, network, params)
    return build_package(out, cfg.name, units, cfg.to_mapping(), inputs, plan, log, sign_key)


def parameter_files(args: argparse.Namespace) -> dict[str, Path]:
    """{unit: path} of --params UNIT=FILE (and --tanh FILE); one line for a bad or repeated unit."""
    pairs = list(args.params) + ([f"tanh={args.tanh}"] if args.tanh is not None else [])
    known = pc.known_units()[1:]
    files: dict[str, Path] = {}
    for pair in pairs:
        unit, sep, path = pair.partition("=")
        if not sep or not path:
            raise HostError(f"--params: expected UNIT=FILE, got {pair[:60]!r}")
        if unit not in known:
            raise HostError(f"--params: unknown unit {unit[:40]!r} (units with a parameter file: {', '.join(known)})")
        if unit in files:
            raise HostError(f"--params: unit {unit} given twice")
        files[unit] = Path(path)
    return files


def summary(result) -> list[str]:
    ev = result.manifest["evidence"]
    step = ev["units"]["controller"]["cycles"]["step"]
    lines = [f"package: {result.folder} ({len(result.manifest['files']) + 1} files, {result.seconds['total']:.1f} s)"]
    lines += [f"  self-test on {t}: {r['selftest_mismatches']} mismatching words"
              for t, r in ev["package_build"].items()]
    lines.append("  whole step worst case (cycle model): " + ", ".join(f"{m} {step[m]['max']}" for m in MODES)
                 + " cycles (paper budget 3.3 ms = 554,400)")
    return lines


def run(args: argparse.Namespace) -> int:
    plan = evidence_plan(args)
    sign_key = load_key(args.sign_key) if args.sign_key is not None else None
    cfg = pc.load(args.config)
    if args.pid_only:
        cfg = dataclasses.replace(cfg, controller=dataclasses.replace(cfg.controller, pid_only=True))
    network = art.load(args.network)
    files = parameter_files(args)
    params = {unit: unit_registry.get(unit).load_params(path) for unit, path in files.items()}
    config_path, network_path = Path(args.config), Path(args.network)
    inputs = {"config": {"file": config_path.name, "sha256": file_sha256(config_path), "values_sha256": cfg.sha256},
              "network": {"file": network_path.name, "sha256": file_sha256(network_path),
                          "payload_sha256": network.sha256, "shape": network.shape_text}}
    bound = package_units(cfg, network, params)      # refuses a missing or unconfigured unit before any output
    for unit, path in files.items():
        inputs[unit] = {"file": path.name, "sha256": file_sha256(path), "values_sha256": bound[unit].values_sha256()}
    result = generate(cfg, network, Path(args.out), inputs, params, plan,
                      input_paths=(args.config, args.network, *files.values(), args.sign_key), sign_key=sign_key,
                      units=bound)
    print("\n".join(summary(result)))
    return 0
