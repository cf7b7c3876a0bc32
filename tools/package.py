"""The flight package, built and checked: sources, self-test, CMakeLists, ICD and a manifest
carrying the evidence measured here (written once for whatever units the package holds).

`build_package` takes bound units (the controller first; the host binds them to the
configuration, the network and its realistic inputs) and:
  1. draws the self-test vectors of each unit and renders every file (codegen.package);
  2. measures the evidence: the bit-exact gate (golden == x86 == ARM, mismatching words per
     target), the self-test vectors themselves on x86 and ARM, the cycle / memory / stack report
     with the reference step as an extra class;
  3. builds the folder with its own CMakeLists for x86-64 and for the STM32F417 (firmware/
     package_image) and runs `<name>_selftest()` natively and in the emulator, where the
     reference step's cycles are measured again in the image a firmware team would link;
  4. writes the ICD and the sealed manifest last; the folder appears atomically, only if every
     figure is in (a failing self-test is recorded, not hidden: the caller decides).
`check_package` verifies a folder against its manifest and can re-run step 3.
"""
from __future__ import annotations

import tempfile
import time
from contextlib import nullcontext
from dataclasses import dataclass, field
from pathlib import Path

from codegen import GENERATOR_VERSION, atomic
from codegen.package import manifest
from codegen.package.cmake import cmake_lists
from codegen.package.icd import render_icd
from codegen.package.selftest import SelftestVectors, make_vectors, selftest_sources
from codegen.unit import Batch, Unit, words
from firmware import arm, x86
from firmware.errors import FirmwareError
from firmware.flags import ARM_CPU, COMMON, GCC_ONLY, PORTABLE
from firmware.package_build import build_image
from tools.cycles import CLOCK_HZ, PAPER_BUDGET_CYCLES
from tools.errors import ToolError
from tools.gate import count_mismatches, run_gate
from tools.m4.profile import MODES
from tools.package_run import run_arm, run_qemu, run_x86
from tools.report import cycle_report
from tools.runners import runner

TARGETS = ("x86", "arm")
# `package check --run` also takes qemu: the ARM image in QEMU's netduinoplus2, a second emulator
RUN_TARGETS = ("x86", "arm", "qemu")


@dataclass(frozen=True)
class EvidencePlan:
    """How much is measured at generation (the defaults take about a minute for the controller)."""

    gate_vectors: int = 20_000
    gate_sequences: int = 4
    sequence_steps: int = 200
    selftest_vectors: int = 256
    cycles_per_class: int = 20
    seed: int = 0


@dataclass
class PackageResult:
    folder: Path
    manifest: dict
    seconds: dict[str, float] = field(default_factory=dict)


def evidence_failures(evidence: dict) -> list[str]:
    """Every way the measured evidence falls short of bit-exact (one phrase each)."""
    out = []
    for kind, ev in evidence["units"].items():
        if not ev["gate"]["pass"]:
            out.append(f"{kind}: the bit-exact gate failed")
        out += [f"{kind}: self-test vectors differ on {t} ({r['mismatches']} words)"
                for t, r in ev["selftest_vectors"]["targets"].items() if r["mismatches"]]
    out += [f"{t}: the built self-test reports {r['selftest_mismatches']} mismatching words"
            for t, r in evidence.get("package_build", {}).items() if r["selftest_mismatches"]]
    return out


# ----------------------------------------------------------------------------- files

def _split_sources(units: dict[str, Unit]) -> dict[str, str]:
    """{package path: text} of every unit's C: headers to include/, sources to src/."""
    merged: dict[str, str] = {}
    for unit in units.values():
        for fname, text in unit.sources().items():
            if merged.get(fname, text) != text:
                raise ToolError(f"package: two units generate different {fname}")
            merged[fname] = text
    return {(f"include/{f}" if f.endswith(".h") else f"src/{f}"): t for f, t in sorted(merged.items())}


def source_files(name: str, units: dict[str, Unit], vectors: list[SelftestVectors]) -> dict[str, str]:
    """Everything but ICD.md and the manifest: sources, self-test, CMakeLists.txt."""
    files = _split_sources(units)
    files.update({f"selftest/{f}": t for f, t in selftest_sources(name, vectors).items()})
    files["CMakeLists.txt"] = cmake_lists(name, _in(files, "include/"), _in(files, "src/"), _in(files, "selftest/"),
                                          list(PORTABLE), GENERATOR_VERSION, gcc_flags=list(GCC_ONLY))
    return files


def _in(files: dict[str, str], folder: str) -> list[str]:
    """File names (without the folder) of the package paths under `folder`."""
    return sorted(p[len(folder):] for p in files if p.startswith(folder))


# ----------------------------------------------------------------------------- evidence

def _quiet(_line: str) -> None:
    pass


def record_bytes(unit: Unit) -> dict[str, int]:
    """sizeof of each C record (input, output, state): the unit's packed dtypes, whose layout the
    harness checks against the C's sizeof and offsetof."""
    dtypes = {"input": unit.input_dtype, "output": unit.output_dtype, "state": unit.state_dtype}
    return {role: d.itemsize for role, d in dtypes.items() if d is not None}


def unit_evidence(unit: Unit, vec: SelftestVectors, plan: EvidencePlan, log=print) -> dict:
    """Gate, self-test vectors on the targets, cycles, memory of one unit."""
    t0 = time.perf_counter()
    gate = run_gate(unit, plan.gate_vectors, plan.gate_sequences if unit.stateful else 0, plan.sequence_steps,
                    plan.seed, TARGETS, log=_quiet)
    selftest = {}
    batch = Batch(vec.state, vec.input)
    for target in TARGETS:
        out, state = runner(unit, target).records(batch)
        bad = count_mismatches(vec.output, out)
        if unit.stateful:
            bad += count_mismatches(vec.state_after, state)
        selftest[target] = {"mismatches": bad}
    log(f"  {unit.kind}: gate {gate.vectors} vectors + {gate.sequences} x {gate.steps} steps, "
        f"{'PASS' if gate.ok else 'FAIL'} ({time.perf_counter() - t0:.1f} s)")
    t1 = time.perf_counter()
    ref = {"reference": Batch(None if vec.state is None else vec.state[:1], vec.input[:1])}
    rep = cycle_report(unit, MODES, plan.cycles_per_class, plan.seed, extra=ref)
    functions = {fn: row["inclusive"] for fn, row in rep["functions"].items()}
    log(f"  {unit.kind}: cycles worst case " + ", ".join(f"{m} {rep['cycles'][m]['max']}" for m in MODES)
        + f" ({time.perf_counter() - t1:.1f} s)")
    return {
        "kind": unit.kind, "entry": unit.entry, "step": unit.step_symbol, "identity": unit.identity(),
        "gate": {"vectors": gate.vectors, "sequences": gate.sequences, "steps": gate.steps, "seed": plan.seed,
                 "classes": gate.counts, "pass": gate.ok,
                 "targets": {"golden": {"invariant_problems": len(gate.problems.get("golden", []))},
                             **{t: {"mismatches": gate.mismatches[t]} for t in TARGETS}}},
        "selftest_vectors": {"n": vec.n, "classes": vec.classes, "targets": selftest,
                             "reference_output_words": [f"0x{w:08x}" for w in words(vec.output[:1])[0]]},
        "cycles": {"step": rep["cycles"], "reference": {m: rep["by_class"]["reference"][m]["max"] for m in MODES},
                   "per_class": plan.cycles_per_class, "table": rep["table"], "bound": rep["bound"],
                   "step_lenient": rep["cycles_lenient"], "functions": functions},
        "memory": {"flash_bytes": rep["flash_bytes"], "ram_bytes": rep["ram_bytes"],
                   "state_bytes": rep["state_bytes"], "stack_bytes": rep["stack_bytes"],
                   "record_bytes": record_bytes(unit),
                   "tables_in": unit.tables_in},
        "budgets": rep["budgets"],
    }


def run_package(folder: Path, name: str, targets=TARGETS, c_flags=(), work: Path | None = None) -> dict:
    """Build the package with its own CMakeLists for each target and run `<name>_selftest()`
    (x86-64 natively, the STM32F417 image in the emulator, where the reference step is profiled).
    The builds go into `work` (generate: a temporary beside the output that a later run removes if
    this one is killed), else into a system temporary folder."""
    out = {}
    with nullcontext(work) if work is not None else tempfile.TemporaryDirectory(prefix="staregen-pkg-") as tmp:
        for target in targets:
            image = build_image(folder, name, target, Path(tmp) / target, c_flags=c_flags)
            if target == "x86":
                out["x86"] = {"selftest_mismatches": run_x86(image)}
            elif target == "qemu":
                run = run_qemu(image)
                out["qemu"] = {"selftest_mismatches": run.mismatches, "reference_output": list(run.output),
                               "seconds": run.seconds}
            else:
                run = run_arm(image, name)
                out["arm"] = {"selftest_mismatches": run.mismatches, "reference_cycles": dict(run.step_cycles),
                              "reference_output": list(run.output), "selftest_cycles": run.selftest_cycles,
                              "selftest_stack_bytes": run.selftest_stack_bytes}
    return out


def build_evidence(units: dict[str, Unit], vectors: list[SelftestVectors], plan: EvidencePlan, log=print) -> dict:
    return {"units": {k: unit_evidence(u, v, plan, log) for (k, u), v in zip(units.items(), vectors)},
            "clock_hz": CLOCK_HZ, "paper_budget_cycles": PAPER_BUDGET_CYCLES, "modes": list(MODES)}


def build_info() -> dict:
    return {"flags": list(COMMON), "arm_cpu": list(ARM_CPU), "required": ["-ffp-contract=off", "-std=c99"],
            "compilers": {"arm": arm.compiler_version(), "x86": x86.compiler_version()},
            "fp_environment": "IEEE 754 binary32, round to nearest even, subnormals kept (FPSCR FZ=0 / "
                              "MXCSR FTZ=DAZ=0)"}


# ----------------------------------------------------------------------------- the package

def build_package(out: str | Path, name: str, units: dict[str, Unit], config: dict, inputs: dict,
                  plan: EvidencePlan = EvidencePlan(), log=print, sign_key: bytes | None = None) -> PackageResult:
    """Write the flight package of `units` (controller first) into `out`, atomically; with
    `sign_key` the manifest carries its HMAC-SHA256 signature (codegen.package.manifest).

    config: the configuration's values (codegen.package.config.PackageConfig.to_mapping());
    inputs: {"config" / "network" / "tanh": {"file": name, "sha256": of the file's bytes, ...}}."""
    out = Path(out)
    if out.exists() and not out.is_dir():
        raise ToolError(f"--out: {out} exists and is not a directory")
    seconds, t0 = {}, time.perf_counter()
    vectors = [make_vectors(u, plan.selftest_vectors, plan.seed) for u in units.values()]
    files = source_files(name, units, vectors)
    seconds["render"] = round(time.perf_counter() - t0, 2)
    try:
        with atomic.directory(out) as tmp, atomic.scratch(out) as work:   # locked from here: a second run fails
            log(f"package {name}: {len(files) + 2} files; measuring the evidence")
            t1 = time.perf_counter()
            evidence = build_evidence(units, vectors, plan, log)
            seconds["evidence"] = round(time.perf_counter() - t1, 2)
            for rel, text in files.items():
                atomic.write_text(tmp / rel, text)
            t2 = time.perf_counter()
            evidence["package_build"] = run_package(tmp, name, work=work)
            seconds["package_build"] = round(time.perf_counter() - t2, 2)
            log("  package build: " + ", ".join(f"{t} self-test {r['selftest_mismatches']} mismatches"
                                                for t, r in evidence["package_build"].items()))
            failures = evidence_failures(evidence)
            if failures:
                raise ToolError("refusing to write the package: " + "; ".join(failures))
            info = build_info()
            files["ICD.md"] = render_icd(name, units, {**config, "inputs": inputs}, evidence, {
                "common": info["flags"], "arm_cpu": info["arm_cpu"], "compiler": info["compilers"]["arm"],
                "signed": sign_key is not None, "gcc_only": list(GCC_ONLY)})
            atomic.write_text(tmp / "ICD.md", files["ICD.md"])
            body = {"generator": {"name": "staregen", "version": GENERATOR_VERSION}, "name": name,
                    "units": {k: {"entry": u.entry, "identity": u.identity()} for k, u in units.items()},
                    "config": config, "inputs": inputs, "build": info, "evidence": evidence}
            doc = manifest.document({p: t.encode("utf-8") for p, t in files.items()}, body, sign_key)
            atomic.write_text(tmp / manifest.MANIFEST, manifest.to_text(doc))
    except OSError as exc:
        raise ToolError(f"cannot write package folder {out}: {exc.strerror or exc}") from None
    seconds["total"] = round(time.perf_counter() - t0, 2)
    return PackageResult(out, doc, seconds)


def _dig(doc, *keys) -> dict:
    """doc[k1][k2]... of a (sealed but otherwise untrusted) manifest; {} where it is not a mapping."""
    for key in keys:
        doc = doc.get(key) if isinstance(doc, dict) else None
    return doc if isinstance(doc, dict) else {}


def _recorded_words(doc: dict) -> list[str] | None:
    """The reference step's output words the manifest recorded from the Unicorn run, if well-formed."""
    words = _dig(doc, "evidence", "package_build", "arm").get("reference_output")
    ok = isinstance(words, list) and all(isinstance(w, str) and len(w) == 8 for w in words)
    return words if ok else None


def _qemu_problems(doc: dict, runs: dict) -> list[str]:
    """The reference step's output words in QEMU against the Unicorn run's (this check's, else the
    manifest's, recorded from the Unicorn run at generation)."""
    want = runs["arm"]["reference_output"] if "arm" in runs else _recorded_words(doc)
    got = runs["qemu"]["reference_output"]
    if not want:
        return ["qemu: no Unicorn reference output to compare with (add arm to --run)"]
    if got != want:
        return [f"qemu: reference step output words {' '.join(got)} differ from the Unicorn run's {' '.join(want)}"]
    return []


def check_package(folder: str | Path, run: tuple[str, ...] = (),
                  key: bytes | None = None) -> tuple[dict, list[str], dict]:
    """(manifest, problems, runs): the folder against its manifest (and its signature under `key`,
    when given) and, for each target in `run`, the self-test built with the package's CMakeLists
    (the ARM reference step's cycles compared to the manifest's, QEMU's output words to Unicorn's).
    A folder that fails its check is never configured, compiled or run: its CMakeLists.txt is code
    (execute_process) and an edited file is untrusted. What is built is a private copy of the
    bytes that were checked."""
    doc, problems = manifest.check(folder, key)
    if problems or not run:
        return doc, problems, {}
    runs = {}
    with tempfile.TemporaryDirectory(prefix="staregen-check-") as tmp:
        problems = manifest.copy_verified(folder, doc, tmp)    # build the bytes checked, not the folder
        for target in run if not problems else ():
            try:
                runs.update(run_package(Path(tmp), doc["name"], (target,)))
            except (FirmwareError, ToolError) as exc:
                problems.append(f"{target}: the package does not build or run: {exc}")
    if "arm" in runs:
        want = _dig(doc, "evidence", "package_build", "arm", "reference_cycles")
        got = runs["arm"]["reference_cycles"]
        if want and got != want:
            problems.append(f"arm: reference step takes {got} cycles, the manifest says {want}")
    if "qemu" in runs:
        problems += _qemu_problems(doc, runs)
    problems += [f"{t}: self-test reports {r['selftest_mismatches']} mismatching words"
                 for t, r in runs.items() if r["selftest_mismatches"] != 0]
    return doc, problems, runs
