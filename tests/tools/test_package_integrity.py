"""Issue 25, integrity of a delivered package: nothing of a package that fails its check is built
or run (defect 5); entries that are not regular files or folders are refused unopened, and no file
is read beyond a cap whatever its size (defect 7); the package's ARM image also runs in QEMU's
netduinoplus2, a second emulator, with the reference step's output words equal to Unicorn's."""
from __future__ import annotations

import os
import resource
import shutil
import subprocess
import sys
import time
from pathlib import Path

import pytest

from codegen.artifact import random_artifact
from codegen.package import manifest
from firmware.package_build import build_image
from host.cli import main
from host.control.nn_controller import default_package_config
from host.sim.scenarios import package_units
from tests.tools.test_package import flip_weight_bit
from tools import package_run
from tools.errors import ToolError
from tools.package import EvidencePlan, build_package, check_package

REPO = Path(__file__).resolve().parents[2]
PLAN = EvidencePlan(gate_vectors=200, gate_sequences=1, sequence_steps=20, selftest_vectors=8, cycles_per_class=1)
CLI = "import sys; from host.cli import main; sys.exit(main())"


@pytest.fixture(scope="module")
def package(tmp_path_factory):
    cfg = default_package_config()
    artifact = random_artifact((12, 40, 3), seed=1)
    return build_package(tmp_path_factory.mktemp("pkg") / "stare", cfg.name, package_units(cfg, artifact),
                         cfg.to_mapping(), {"network": {"sha256": artifact.sha256}}, PLAN, log=lambda _line: None)


@pytest.fixture()
def folder(package, tmp_path) -> Path:
    dst = tmp_path / "copy"
    shutil.copytree(package.folder, dst)
    return dst


def _limited_memory() -> None:
    resource.setrlimit(resource.RLIMIT_AS, (3 << 30, 3 << 30))   # reading 8 GB fails fast, never swaps


def check_in_subprocess(folder: Path, *extra: str, timeout: float = 60) -> subprocess.CompletedProcess:
    """`package check` in a child with 3 GB of address space and a time-out: a check that blocks on
    a FIFO or reads a huge file fails this test instead of hanging or exhausting the machine."""
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


def test_an_intact_package_still_runs(package):
    _, problems, runs = check_package(package.folder, ("x86",))
    assert problems == [] and runs["x86"]["selftest_mismatches"] == 0


# ----------------------------------------------------------------------------- defect 7

def test_fifo_among_the_sources_is_refused_unopened(folder):
    os.mkfifo(folder / "src" / "evil.c")
    (folder / "src" / "sg_math.c").unlink()
    os.mkfifo(folder / "src" / "sg_math.c")          # a listed path too: opening it would block
    res = check_in_subprocess(folder, timeout=30)
    assert res.returncode == 1, res.stderr
    assert res.stdout.splitlines() == [f"{folder}: not a regular file or folder: src/evil.c",
                                       f"{folder}: not a regular file or folder: src/sg_math.c"]


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
    res = check_in_subprocess(folder, timeout=30)
    assert res.returncode == 2 and "manifest.json: not a regular file" in res.stderr
    assert res.stderr.count("\n") == 1


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
