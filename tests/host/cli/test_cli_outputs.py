"""Issue 25, data loss: `generate` and `tune pid` write only a new or empty folder or their own earlier
output (a package whose manifest lists everything in it; a tuning folder), never a folder holding an
input or the current folder; the output is locked while written and a killed run's temporaries
(beside the output, none in the system temp folder) are removed by the next run."""
from __future__ import annotations

import fcntl
import json
import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

from codegen import atomic
from codegen.package import manifest
from host.errors import HostError
from host.tune.pid_tuning import PLAN_FILE, TuningPlan, open_directory
from host.tune.pid_grid import PidGrid
from host.sim.targets import staring_targets
from tests.host.cli.package_inputs import cli, package_inputs

ROOT = Path(__file__).resolve().parents[3]
SMALL = ["--gate-vectors", "1000", "--vectors", "32", "--cycles-per-class", "3"]
# A package build killed (SIGKILL) when it starts compiling: what does it leave behind?
KILLED_BUILD = """
import os, signal, sys
import tools.package as tp
from codegen.artifact import random_artifact
from host.control.nn_controller import default_package_config
from host.sim.scenarios import package_units

tp.build_image = lambda *args, **kw: os.kill(os.getpid(), signal.SIGKILL)
cfg = default_package_config()
units = package_units(cfg, random_artifact((12, 40, 3), seed=1), None)
plan = tp.EvidencePlan(gate_vectors=200, gate_sequences=1, sequence_steps=20, selftest_vectors=8, cycles_per_class=1)
tp.build_package(sys.argv[1], cfg.name, units, cfg.to_mapping(), {}, plan, log=lambda _line: None)
"""


@pytest.fixture()
def inputs(tmp_path):
    folder = tmp_path / "in"
    folder.mkdir()
    return package_inputs(folder)


def generate(capsys, inputs, out, *extra):
    cfg, net = inputs
    return cli(capsys, "generate", "--config", str(cfg), "--network", str(net), "--out", str(out), *SMALL, *extra)


def tree(folder: Path) -> dict[str, bytes]:
    return {p.relative_to(folder).as_posix(): p.read_bytes() for p in sorted(folder.rglob("*")) if p.is_file()}


def fake_package(folder: Path) -> None:
    """A folder holding exactly what its (valid, sealed) staregen manifest lists."""
    files = {"src/stare.c": b"/* old */\n", "include/stare.h": b"/* old */\n", "ICD.md": b"# old\n"}
    for rel, data in files.items():
        (folder / rel).parent.mkdir(parents=True, exist_ok=True)
        (folder / rel).write_bytes(data)
    (folder / manifest.MANIFEST).write_text(manifest.to_text(manifest.document(files, {"name": "stare"})))


def assert_one_line_refusal(code, err, message):
    assert code == 2 and err.count("\n") == 1 and "Traceback" not in err and message in err, (code, err)


# ----------------------------------------------------------------------------- defect 1

def test_generate_refuses_a_folder_with_a_foreign_manifest(tmp_path, capsys, inputs):
    w = tmp_path / "w"
    (w / "src").mkdir(parents=True)
    (w / "manifest.json").write_text('{"name":"ext"}\n')
    (w / "src" / "app.js").write_text("x\n")
    before = tree(w)
    code, _, err = generate(capsys, inputs, w)
    assert_one_line_refusal(code, err, "not this command's own output")
    assert "format" in err and tree(w) == before
    assert sorted(p.name for p in tmp_path.iterdir()) == ["in", "w"]


def test_generate_refuses_a_package_folder_holding_other_files(tmp_path, capsys, inputs):
    w = tmp_path / "w"
    fake_package(w)
    (w / "src" / "notes.txt").write_text("mine\n")
    before = tree(w)
    code, _, err = generate(capsys, inputs, w)
    assert_one_line_refusal(code, err, "src/notes.txt is not a file of the package's manifest")
    assert tree(w) == before


def test_generate_refuses_an_input_inside_the_output(tmp_path, capsys, inputs):
    cfg, net = inputs
    code, _, err = generate(capsys, (cfg, net), cfg.parent)
    assert_one_line_refusal(code, err, f"input {cfg} lies inside output folder {cfg.parent}")
    assert sorted(p.name for p in cfg.parent.iterdir()) == ["controller.toml", "network.json"]


@pytest.mark.parametrize("out", [".", "..", "/"])
def test_generate_into_the_current_folder_or_above_is_one_line(tmp_path, capsys, monkeypatch, inputs, out):
    here = tmp_path / "empty"
    here.mkdir()
    monkeypatch.chdir(here)
    code, _, err = generate(capsys, inputs, out)
    assert_one_line_refusal(code, err, "is the current folder or holds it")
    assert list(here.iterdir()) == [] and sorted(p.name for p in tmp_path.iterdir()) == ["empty", "in"]


def test_generate_replaces_exactly_a_package_and_leaves_nothing_beside_it(tmp_path, capsys, inputs):
    w = tmp_path / "w"
    fake_package(w)
    code, out, err = generate(capsys, inputs, w)
    assert code == 0, err
    assert manifest.check(w)[1] == [] and b"/* old */" not in (w / "src" / "stare.c").read_bytes()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["in", "w"]   # no lock, temporary or old copy


# ----------------------------------------------------------------------------- defect 4

def hold_lock(folder: Path) -> int:
    """Lock `folder` as a concurrent run does: flock on `.<name>.lock` beside it."""
    fd = os.open(folder.with_name(f".{folder.name}.lock"), os.O_RDWR | os.O_CREAT)
    fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
    return fd


def test_a_second_generate_into_a_locked_folder_fails_in_one_line(tmp_path, capsys, inputs):
    w = tmp_path / "w"
    fd = hold_lock(w)
    try:
        code, _, err = generate(capsys, inputs, w)
    finally:
        os.close(fd)
    assert_one_line_refusal(code, err, "is in use by another run")
    assert sorted(p.name for p in tmp_path.iterdir()) == [".w.lock", "in"]


def test_a_killed_generate_leaves_only_temporaries_the_next_run_removes(tmp_path):
    system_tmp, parent = tmp_path / "system-tmp", tmp_path / "out"
    system_tmp.mkdir()
    parent.mkdir()
    out = parent / "pkg"
    proc = subprocess.Popen([sys.executable, "-c", KILLED_BUILD, str(out)], cwd=ROOT, stderr=subprocess.PIPE, text=True,
                            env={**os.environ, "TMPDIR": str(system_tmp)})
    _, stderr = proc.communicate(timeout=600)
    assert proc.returncode == -9, stderr
    assert list(system_tmp.iterdir()) == []                     # no staregen-pkg-* in the system temp folder
    left = sorted(p.name for p in parent.iterdir())
    ours = re.compile(rf"\.pkg\.{proc.pid}\.[a-z0-9_]{{8}}\.tmp")
    assert ".pkg.lock" in left and len(left) >= 2 and all(ours.fullmatch(n) for n in left if n != ".pkg.lock"), left
    with atomic.directory(out) as tmp:                           # the next run into the same folder
        (tmp / "f").write_text("1")
    assert sorted(p.name for p in parent.iterdir()) == ["pkg"]


# ----------------------------------------------------------------------------- defect 3

TINY = PidGrid("tiny", (17.0,), (0.0,), (46.0,))


def tiny_plan() -> TuningPlan:
    targets = tuple((t.name, t.lon, t.lat, i) for i, t in enumerate(staring_targets()[:1]))
    return TuningPlan(grid=TINY, targets=targets, seeds=(0,), duration=11.0, shard_size=1)


def test_tune_refuses_a_folder_that_is_not_a_tuning_folder(tmp_path):
    work = tmp_path / "work"
    work.mkdir()
    (work / "controller.toml").write_text("# my hand-tuned gains\n")
    (work / "result.json").write_text('{"mine": true}\n')
    before = tree(work)
    with pytest.raises(HostError, match="not this command's own output .it holds no tuning.json"):
        open_directory(work, tiny_plan())
    assert tree(work) == before


def test_tune_pid_cli_refuses_a_foreign_folder_in_one_line(tmp_path, capsys):
    work = tmp_path / "work"
    work.mkdir()
    (work / "controller.toml").write_text("# my hand-tuned gains\n")
    code, _, err = cli(capsys, "tune", "pid", "--grid", "kp=17,ki=0,kd=46", "--targets", "1", "--duration", "11",
                       "--workers", "1", "--no-progress", "--out", str(work))
    assert_one_line_refusal(code, err, "refusing to write into it")
    assert sorted(p.name for p in work.iterdir()) == ["controller.toml"]


def test_tune_opens_a_new_an_empty_or_its_own_folder(tmp_path):
    plan = tiny_plan()
    assert open_directory(tmp_path / "new", plan) == []
    (tmp_path / "empty").mkdir()
    assert open_directory(tmp_path / "empty", plan) == []
    (tmp_path / "new" / "result.json").write_text("{}")         # its own folder, resumed
    assert open_directory(tmp_path / "new", plan) == []
    assert json.loads((tmp_path / "new" / PLAN_FILE).read_text())["plan_hash"] == plan.plan_hash()
