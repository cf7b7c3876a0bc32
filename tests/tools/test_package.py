"""The flight package end to end: generated, built with its own CMakeLists for the STM32F417 and
x86-64, self-tested, deterministic, and planted faults caught (issue 12 acceptance)."""
from __future__ import annotations

import re
import shutil
import subprocess
from pathlib import Path

import pytest

from codegen.artifact import random_artifact
from codegen.package import manifest
from codegen.units.gp.example import example_params as gp_example_params
from codegen.units.rbf.params import example_params as rbf_example_params
from codegen.units.tanh.params import example_params
from firmware.errors import FirmwareError
from firmware.package_build import build_image
from host.control.nn_controller import default_package_config
from host.sim.scenarios import package_units
from tools.package import EvidencePlan, build_package, check_package
from tools.package_run import run_arm, run_x86

PLAN = EvidencePlan(gate_vectors=2_000, gate_sequences=2, sequence_steps=100, selftest_vectors=128,
                    cycles_per_class=5)
ARTIFACT = random_artifact((12, 40, 3), seed=1)


def generate(out: Path, cfg=None, params: dict | None = None):
    cfg = cfg or default_package_config()
    units = package_units(cfg, ARTIFACT, params)
    return build_package(out, cfg.name, units, cfg.to_mapping(), {"network": {"sha256": ARTIFACT.sha256}},
                         PLAN, log=lambda _line: None)


@pytest.fixture(scope="module")
def package(tmp_path_factory):
    return generate(tmp_path_factory.mktemp("pkg") / "stare")


def copy_of(package, tmp_path) -> Path:
    dst = tmp_path / "copy"
    shutil.copytree(package.folder, dst)
    return dst


def test_layout_and_manifest(package):
    folder, doc = package.folder, package.manifest
    files = sorted(p.relative_to(folder).as_posix() for p in folder.rglob("*") if p.is_file())
    assert files == sorted([*doc["files"], "manifest.json"])
    assert {"include/stare.h", "include/stare_nn.h", "include/sg_math.h", "src/stare.c", "src/stare_nn.c",
            "src/sg_math.c", "selftest/stare_selftest.c", "selftest/stare_selftest.h", "CMakeLists.txt",
            "ICD.md"} == set(doc["files"])
    ev = doc["evidence"]["units"]["controller"]
    assert ev["gate"]["pass"] and ev["gate"]["targets"]["x86"]["mismatches"] == 0
    assert ev["gate"]["targets"]["arm"]["mismatches"] == 0 and ev["gate"]["vectors"] == PLAN.gate_vectors
    assert all(ev["cycles"]["step"][m]["min"] <= ev["cycles"]["step"][m]["max"] for m in ("ideal", "art", "pessimistic"))
    assert ev["memory"]["flash_bytes"] > 0 and ev["memory"]["stack_bytes"] > 0
    assert doc["build"]["flags"][0] == "-std=c99" and "-ffp-contract=off" in doc["build"]["flags"]
    assert manifest.check(folder)[1] == []
    text = (folder / "manifest.json").read_text()
    assert not re.search(r"20\d\d-\d\d-\d\d", text) and "/tmp" not in text     # no dates, no local paths


def test_cmake_image_on_the_stm32f417_matches_the_manifest(package, tmp_path):
    elf = build_image(package.folder, "stare", "arm", tmp_path / "arm")
    run = run_arm(elf, "stare")
    assert run.mismatches == 0
    recorded = package.manifest["evidence"]["package_build"]["arm"]["reference_cycles"]
    assert run.step_cycles == recorded                        # same image, same cycles in every mode
    harness = package.manifest["evidence"]["units"]["controller"]["cycles"]["reference"]
    assert run.step_cycles["ideal"] == harness["ideal"]       # the harness build of the same step agrees
    assert run.status & 1 == 0                                # the reference step flies the network


def test_cmake_image_on_x86(package, tmp_path):
    assert run_x86(build_image(package.folder, "stare", "x86", tmp_path / "x86")) == 0


def test_generation_is_deterministic(package, tmp_path):
    again = generate(tmp_path / "again")
    for rel in [*package.manifest["files"], "manifest.json"]:
        assert (package.folder / rel).read_bytes() == (again.folder / rel).read_bytes(), rel


def flip_weight_bit(folder: Path) -> None:
    """Flip the top mantissa bit (bit 22) of the first hidden-layer weight W1'[0][0] (folded)."""
    path = folder / "src" / "stare_nn.c"
    text = path.read_text()
    at = text.index("/* W1' */")
    m = re.compile(r"0x1\.([0-9a-f])").search(text, at)
    digit = format(int(m.group(1), 16) ^ 8, "x")
    path.write_text(text[:m.start(1)] + digit + text[m.end(1):])


def test_flipped_weight_bit_is_caught_twice(package, tmp_path):
    folder = copy_of(package, tmp_path)
    flip_weight_bit(folder)
    _, problems = manifest.check(folder)
    assert problems == ["edited file: src/stare_nn.c (sha256 differs from the manifest)"]
    run = run_arm(build_image(folder, "stare", "arm", tmp_path / "arm"), "stare")
    assert run.mismatches > 0
    assert run_x86(build_image(folder, "stare", "x86", tmp_path / "x86")) > 0
    _, problems, runs = check_package(folder, ("x86",))      # an edited package is not built (issue 25)
    assert problems == ["edited file: src/stare_nn.c (sha256 differs from the manifest)"] and runs == {}


def test_missing_extra_and_manifest_edits(package, tmp_path):
    folder = copy_of(package, tmp_path)
    (folder / "include" / "stare_nn.h").unlink()
    (folder / "src" / "extra.c").write_text("int x;\n")
    _, problems = manifest.check(folder)
    assert problems == ["missing file: include/stare_nn.h", "extra file: src/extra.c"]
    text = (folder / "manifest.json").read_text()
    (folder / "manifest.json").write_text(text.replace('"pass": true', '"pass": false', 1))
    with pytest.raises(manifest.PackageError, match="edited after it was sealed"):
        manifest.check(folder)


@pytest.mark.parametrize("target", ["arm", "x86"])
def test_fast_math_build_is_refused_by_the_guard(package, tmp_path, target):
    # the package's own later -fexcess-precision=standard clears __FAST_MATH__ (GCC defines it only
    # while every fast-math sub-option holds), so the finite-math-only guard is the one that fires
    with pytest.raises(FirmwareError, match=r'#error "sg_math: built with -f(fast|finite)-math'):
        build_image(package.folder, "stare", target, tmp_path / target, c_flags=["-ffast-math"])


def test_gnu_mode_without_contraction_off_is_refused(package, tmp_path):
    src = package.folder / "src" / "sg_math.c"
    inc = package.folder / "include"
    bad = subprocess.run(["gcc", "-std=gnu99", "-O2", "-I", str(inc), "-c", str(src), "-o", str(tmp_path / "a.o")],
                         capture_output=True, text=True)
    assert bad.returncode != 0 and "GNU C mode contracts a*b+c" in bad.stderr
    ok = subprocess.run(["gcc", "-std=gnu99", "-O2", "-ffp-contract=off", "-DSG_FP_CONTRACT_OFF", "-fno-math-errno", "-I", str(inc),
                         "-c", str(src), "-o", str(tmp_path / "b.o")], capture_output=True, text=True)
    assert ok.returncode == 0, ok.stderr


def test_check_package_reruns_the_selftest(package):
    doc, problems, runs = check_package(package.folder, ("x86", "arm"))
    assert problems == [] and runs["x86"]["selftest_mismatches"] == 0
    assert runs["arm"]["reference_cycles"] == doc["evidence"]["package_build"]["arm"]["reference_cycles"]


def test_package_with_the_tanh_and_rbf_laws(tmp_path):
    """Every registered unit with a parameter file joins a package by configuration alone."""
    cfg = default_package_config()
    cfg = type(cfg)(cfg.name, ("controller", "rbf", "tanh"), cfg.controller)
    result = generate(tmp_path / "all", cfg, {"tanh": example_params(), "rbf": rbf_example_params()})
    for name in ("src/stare_tanh.c", "src/stare_rbf.c", "include/stare_rbf.h"):
        assert name in result.manifest["files"]
    assert set(result.manifest["evidence"]["units"]) == {"controller", "rbf", "tanh"}
    assert result.manifest["evidence"]["package_build"]["arm"]["selftest_mismatches"] == 0
    assert result.manifest["evidence"]["package_build"]["x86"]["selftest_mismatches"] == 0
    icd = (result.folder / "ICD.md").read_text()
    assert "## Unit `rbf`: `stare_rbf`" in icd and "`stare_rbf_state_t`" in icd


def test_package_with_the_gp_law(tmp_path):
    """The stateless GP law joins a package the same way; its ICD states its fields and status bits."""
    cfg = default_package_config()
    cfg = type(cfg)(cfg.name, ("controller", "gp"), cfg.controller)
    result = generate(tmp_path / "gp", cfg, {"gp": gp_example_params()})
    for name in ("src/stare_gp.c", "include/stare_gp.h"):
        assert name in result.manifest["files"]
    assert result.manifest["evidence"]["package_build"]["arm"]["selftest_mismatches"] == 0
    assert result.manifest["evidence"]["package_build"]["x86"]["selftest_mismatches"] == 0
    icd = (result.folder / "ICD.md").read_text()
    assert "## Unit `gp`: `stare_gp`" in icd and "STATUS_VAR_FLOOR" in icd and "(N*m)^2" in icd
    assert "`stare_gp_step` has no period of its own and no state: call it once per control period" in icd
    assert "None" not in icd
