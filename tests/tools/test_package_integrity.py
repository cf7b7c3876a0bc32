"""Issue 25, integrity of a delivered package: nothing of a package that fails its check is built
or run (defect 5); entries that are not regular files or folders are refused unopened, and no file
is read beyond a cap whatever its size (defect 7); every FP-environment bit the ICD names is
caught by the self-test on the STM32F417 image, or proven not to change any output (FPSCR.DN,
defect 20; the x86 MXCSR bits: tests/codegen/package/test_selftest.py); the package's ARM image
also runs in QEMU's netduinoplus2, a second emulator, with the reference step's output words equal
to Unicorn's."""
from __future__ import annotations

import os
import resource
import shutil
import subprocess
import sys
import threading
import time
from pathlib import Path

import numpy as np
import pytest
from unicorn import arm_const as R

from codegen.artifact import random_artifact
from codegen.unit import Batch
from codegen.package import manifest
from firmware.package_build import build_image
from host.cli import main
from host.control.nn_controller import default_package_config
from host.sim import tanh_example
from host.sim.scenarios import configure_unit, package_units
from tests.tools.test_package import flip_weight_bit
from tools import package_run
from tools.errors import ToolError
from tools.gate import count_mismatches
from tools.m4.elf import Image
from tools.m4.harness import Harness
from tools.m4.machine import Machine
from tools.package import EvidencePlan, build_package, check_package
from tools.runners import arm_build, pack, unpack

REPO = Path(__file__).resolve().parents[2]
PLAN = EvidencePlan(gate_vectors=200, gate_sequences=1, sequence_steps=20, selftest_vectors=8, cycles_per_class=1)
CLI = "import sys; from host.cli import main; sys.exit(main())"
FZ, DN = 1 << 24, 1 << 25
RMODE = {"plus-inf": 1 << 22, "minus-inf": 2 << 22, "zero": 3 << 22}
ARTIFACT = random_artifact((12, 40, 3), seed=1)


@pytest.fixture(scope="module")
def package(tmp_path_factory):
    cfg = default_package_config()
    return build_package(tmp_path_factory.mktemp("pkg") / "stare", cfg.name, package_units(cfg, ARTIFACT),
                         cfg.to_mapping(), {"network": {"sha256": ARTIFACT.sha256}}, PLAN, log=lambda _line: None)


@pytest.fixture()
def folder(package, tmp_path) -> Path:
    dst = tmp_path / "copy"
    shutil.copytree(package.folder, dst)
    return dst


def _limited_memory() -> None:
    resource.setrlimit(resource.RLIMIT_AS, (3 << 30, 3 << 30))   # reading 8 GB fails fast, never swaps


def check_within(folder: Path, seconds: float):
    """manifest.check in a daemon thread: ("done", problems), ("error", exception), or ("blocked",
    None) when it did not return in `seconds` (a check that opened a FIFO would wait forever)."""
    result = ["blocked", None]

    def work():
        try:
            result[:] = ["done", manifest.check(folder)[1]]
        except manifest.PackageError as exc:
            result[:] = ["error", exc]
    thread = threading.Thread(target=work, daemon=True)
    thread.start()
    thread.join(seconds)
    return tuple(result)


def check_in_subprocess(folder: Path, *extra: str, timeout: float = 60) -> subprocess.CompletedProcess:
    """`package check` in a child with 3 GB of address space and a time-out: a check that reads a
    huge file fails this test instead of exhausting the machine."""
    return subprocess.run([sys.executable, "-c", CLI, "package", "check", str(folder), *extra], cwd=REPO,
                          capture_output=True, text=True, timeout=timeout, preexec_fn=_limited_memory, check=False)


# ----------------------------------------------------------------------------- defect 5

def test_edited_cmakelists_is_neither_configured_nor_run(folder, tmp_path, capsys):
    marker = tmp_path / "marker"
    cmake = folder / "CMakeLists.txt"
    cmake.write_text(cmake.read_text() + f'execute_process(COMMAND touch "{marker}")\n')
    code = main(["package", "check", str(folder), "--run", "x86"])
    out = capsys.readouterr().out
    assert code == 1 and f"{folder}: edited file: CMakeLists.txt" in out
    assert not marker.exists()                     # CMake never saw the edited file
    doc, problems, runs = check_package(folder, ("x86", "arm"))
    assert runs == {} and problems == ["edited file: CMakeLists.txt (sha256 differs from the manifest)"]
    assert not marker.exists()


def test_only_the_bytes_checked_are_copied_for_the_build(folder, tmp_path):
    doc, problems = manifest.check(folder)
    assert problems == []
    cmake = folder / "CMakeLists.txt"
    cmake.write_text(cmake.read_text() + "execute_process(COMMAND true)\n")   # swapped after the check
    problems = manifest.copy_verified(folder, doc, tmp_path / "build")
    assert problems == ["changed during the check: CMakeLists.txt (sha256 differs from the manifest)"]
    assert not (tmp_path / "build" / "CMakeLists.txt").exists()
    assert (tmp_path / "build" / "src" / "stare.c").read_bytes() == (folder / "src" / "stare.c").read_bytes()


def test_an_intact_package_still_runs(package):
    _, problems, runs = check_package(package.folder, ("x86",))
    assert problems == [] and runs["x86"]["selftest_mismatches"] == 0


def test_unsigned_package_says_what_its_seal_means(package):
    icd = " ".join((package.folder / "ICD.md").read_text().split())
    assert "The seal catches accidents (a truncated copy, a stray edit, a lost file), not tampering" in icd
    assert "This manifest is not signed" in icd and "signature" not in package.manifest


# ----------------------------------------------------------------------------- defect 7

def test_fifo_among_the_sources_is_refused_unopened(folder):
    os.mkfifo(folder / "src" / "evil.c")
    (folder / "src" / "sg_math.c").unlink()
    os.mkfifo(folder / "src" / "sg_math.c")          # a listed path too: opening it would block
    assert check_within(folder, 10) == ("done", ["not a regular file or folder: src/evil.c",
                                                 "not a regular file or folder: src/sg_math.c"])


def test_symlinks_are_refused(folder):
    (folder / "src" / "link.c").symlink_to(folder / "src" / "stare.c")
    (folder / "ICD.md").unlink()
    (folder / "ICD.md").symlink_to(REPO / "README.md")
    (folder / "more").symlink_to(folder / "src", target_is_directory=True)
    _, problems = manifest.check(folder)
    assert problems == ["not a regular file or folder: ICD.md", "not a regular file or folder: more",
                        "not a regular file or folder: src/link.c"]


def test_manifest_that_is_a_fifo_is_refused_unopened(folder):
    (folder / "manifest.json").unlink()
    os.mkfifo(folder / "manifest.json")
    state, error = check_within(folder, 10)
    assert state == "error" and str(error) == f"{folder / 'manifest.json'}: not a regular file (refused unopened)"


def test_huge_sparse_files_are_not_read(folder):
    for rel in ("src/stare.c", "src/huge.c"):             # a listed file and an extra one, 8 GB each
        with open(folder / rel, "wb") as f:
            f.truncate(8 << 30)
    res = check_in_subprocess(folder, timeout=20)
    assert res.returncode == 1, res.stderr[-500:]
    assert res.stdout.splitlines() == [
        f"{folder}: edited file: src/stare.c (larger than {manifest.MAX_FILE_BYTES} bytes; not read)",
        f"{folder}: extra file: src/huge.c"]


def test_a_file_that_grows_past_its_size_is_capped(tmp_path):
    path = tmp_path / "f"
    path.write_bytes(b"x" * 100)
    assert manifest.read_regular(path, 100) == b"x" * 100
    assert manifest.read_regular(path, 99) is None
    assert manifest.file_sha256(path, 99) is None


# ----------------------------------------------------------------------------- QEMU

def test_package_runs_in_qemu_as_in_the_cortex_m4_emulator(package, capsys):
    doc, problems, runs = check_package(package.folder, ("x86", "arm", "qemu"))
    assert problems == [] and {t: r["selftest_mismatches"] for t, r in runs.items()} == {"x86": 0, "arm": 0, "qemu": 0}
    words = runs["qemu"]["reference_output"]
    assert len(words) >= 4 and words == runs["arm"]["reference_output"]      # bit for bit, as hex words
    assert words == doc["evidence"]["package_build"]["arm"]["reference_output"]
    assert runs["qemu"]["seconds"] < package_run.QEMU_TIMEOUT_S
    code = main(["package", "check", str(package.folder), "--run", "qemu"])   # against the manifest's words
    out = capsys.readouterr().out
    assert code == 0 and f"qemu: self-test 0 mismatching words; reference step output {' '.join(words)}" in out


def test_qemu_catches_a_flipped_weight_bit(package, tmp_path):
    folder = tmp_path / "copy"
    shutil.copytree(package.folder, folder)
    flip_weight_bit(folder)
    run = package_run.run_qemu(build_image(folder, "stare", "qemu", tmp_path / "qemu"))
    assert run.mismatches > 0


def test_a_hung_qemu_is_killed_at_its_time_out(package, monkeypatch):
    monkeypatch.setattr(package_run, "qemu_command", lambda elf: ["sleep", "60"])
    t0 = time.perf_counter()
    with pytest.raises(ToolError, match=r"did not finish within 0.5 s \(killed\)"):
        package_run.run_qemu(package.folder / "ICD.md", timeout=0.5)
    assert time.perf_counter() - t0 < 10


# ----------------------------------------------------------------------------- defect 20 (ARM)

def selftest_under(elf: Path, fpscr: int) -> tuple[int, int]:
    """(mismatches, environment bits) of `stare_selftest()` in the image with FPSCR set after start-up."""
    machine = Machine(Image(elf))
    machine.boot()
    machine.set_fpscr(fpscr)
    return (machine.call("stare_selftest", max_insns=200_000_000),
            machine.call("stare_selftest_fp_environment", max_insns=10_000))


@pytest.fixture(scope="module")
def arm_image(package, tmp_path_factory) -> Path:
    return build_image(package.folder, "stare", "arm", tmp_path_factory.mktemp("arm"))


@pytest.mark.parametrize("fpscr, env", [(0, 0), (FZ, 1 | 16), (RMODE["plus-inf"], 4), (RMODE["minus-inf"], 2),
                                        (RMODE["zero"], 2 | 4), (FZ | DN, 1 | 16)],
                         ids=["ieee", "FZ", "RP", "RM", "RZ", "FZ+DN"])
def test_arm_selftest_catches_flush_to_zero_and_every_rounding_mode(arm_image, fpscr, env):
    mismatches, got = selftest_under(arm_image, fpscr)
    assert got == env
    assert (mismatches == 0) == (env == 0) and mismatches >= bin(env).count("1")


def _random_bits(unit, n: int, seed: int) -> Batch:
    """Records of random bits: NaNs of every payload and sign, subnormals, infinities."""
    words = np.random.default_rng(seed).integers(0, 2**32, (n, unit.input_dtype.itemsize // 4), dtype=np.uint32)
    return Batch(unit.init_state(n) if unit.stateful else None, words.view(unit.input_dtype).reshape(-1))


def _arm_records(unit, batch: Batch, fpscr: int):
    harness = Harness(arm_build(unit, "records").elf, max_insns_per_record=unit.max_instructions)
    harness.machine.set_fpscr(fpscr)
    rec = pack(unit, batch)
    return unpack(unit, harness.run(rec.view(np.uint8).reshape(rec.shape[0], -1)))


def test_default_nan_mode_is_in_effect_in_the_emulator(arm_image):
    """What makes the test below mean something: after set_fpscr(DN) a NaN operand's payload and
    sign are replaced by the default NaN's (vadd.f32 s0, s0, s1; bx lr on -NaN(0x000001) + 1)."""
    machine = Machine(Image(arm_image))
    machine.boot()
    code = 0x0F000200                                   # the emulator's reserved return page, unused here
    machine.write(code, bytes.fromhex("30ee200a7047"))
    results = []
    for fpscr in (0, DN):
        machine.set_fpscr(fpscr)
        machine.uc.reg_write(R.UC_ARM_REG_S0, 0xFFC00001)
        machine.uc.reg_write(R.UC_ARM_REG_S1, 0x3F800000)
        machine.call(code, max_insns=10)
        results.append(machine.uc.reg_read(R.UC_ARM_REG_S0))
    assert results == [0xFFC00001, 0x7FC00000]


@pytest.mark.parametrize("kind", ["controller", "tanh"])
def test_default_nan_mode_changes_no_output_word(kind, arm_image):
    """FPSCR.DN only replaces a NaN result's payload and sign by the default NaN's; every NaN the
    units let out is canonical, so over every gate class and random bits (NaN payloads included)
    no output or state word changes, and the ICD allows DN = 0 or 1. The self-test agrees."""
    inputs = {"artifact": ARTIFACT} if kind == "controller" else {"params": tanh_example.paper_parameters()}
    unit = configure_unit(kind, **inputs)
    classes = [b for b in unit.gate_classes(4_000, 0).values() if b.input.shape[0] > 0]
    gate = Batch(np.concatenate([b.state for b in classes]) if unit.stateful else None,
                 np.concatenate([b.input for b in classes]))
    for batch in (gate, _random_bits(unit, 4_000, 1)):
        out0, state0 = _arm_records(unit, batch, 0)
        out1, state1 = _arm_records(unit, batch, DN)
        golden, golden_state = unit.golden(None if batch.state is None else batch.state.copy(), batch.input)
        assert count_mismatches(golden, out0) == 0            # DN = 0 is the golden model
        assert count_mismatches(out0, out1) == 0              # ... and so is DN = 1, word for word
        if unit.stateful:
            assert count_mismatches(golden_state, state0) == 0 and count_mismatches(state0, state1) == 0
    assert selftest_under(arm_image, DN) == (0, 0)
