"""Issue 14 defect 6: output folders written all or nothing, cache entries verified before use,
a network too large for flash named with its sizes."""
from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

from codegen.artifact import random_artifact
from codegen.units.network.unit import NetworkUnit
from firmware.errors import FirmwareError
from host.cli import main
from tools.runners import arm_build

LOAD = """
import sys
import numpy as np
from codegen.artifact import random_artifact
from codegen.units.network.unit import NetworkUnit
from tools.runners import X86Runner
unit = NetworkUnit(random_artifact((4, 5, 2), seed=3))
run = X86Runner(unit)
out, _ = run.records(unit.gate_classes(50, 0)["inside"])
print(run.build.folder)
"""


def load_in_subprocess(cache: Path) -> subprocess.CompletedProcess:
    env = dict(os.environ, STAREGEN_CACHE=str(cache))
    return subprocess.run([sys.executable, "-c", LOAD], capture_output=True, text=True, env=env, timeout=300)


def test_a_directory_in_the_way_writes_nothing(tmp_path, capsys):
    out = tmp_path / "c"
    (out / "sg_math.h").mkdir(parents=True)
    artifact = tmp_path / "a.json"
    random_artifact((4, 5, 2), seed=1).save(artifact)
    code = main(["codegen", "--artifact", str(artifact), "--out", str(out)])
    err = capsys.readouterr().err
    assert code == 2 and err.count("\n") == 1 and "is not a regular file; nothing was written" in err
    assert sorted(p.name for p in out.iterdir()) == ["sg_math.h"]       # no partial output, no temporaries


def test_a_truncated_cached_module_is_rebuilt_not_loaded(tmp_path):
    cache = tmp_path / "cache"
    first = load_in_subprocess(cache)
    assert first.returncode == 0, first.stderr
    folder = Path(first.stdout.strip().splitlines()[-1])
    module = folder / json.loads((folder / "manifest.json").read_text())["module"]
    module.write_bytes(module.read_bytes()[:4096])                     # truncated: SIGBUS if loaded
    second = load_in_subprocess(cache)
    assert second.returncode == 0, (second.returncode, second.stderr[-500:])
    assert module.stat().st_size > 4096                                  # rebuilt in place


def test_an_edited_cached_elf_is_rebuilt(tmp_path, monkeypatch):
    monkeypatch.setenv("STAREGEN_CACHE", str(tmp_path / "cache"))
    unit = NetworkUnit(random_artifact((4, 5, 2), seed=4))
    build = arm_build(unit)
    original = build.elf.read_bytes()
    build.elf.write_bytes(original[:-16] + b"\0" * 16)
    again = arm_build(unit)
    assert again.elf.read_bytes() == original


def test_a_network_too_large_for_flash_names_the_sizes(tmp_path, monkeypatch):
    monkeypatch.setenv("STAREGEN_CACHE", str(tmp_path / "cache"))
    unit = NetworkUnit(random_artifact((12, 20_000, 3), seed=1))
    with pytest.raises(FirmwareError) as exc:
        arm_build(unit)
    text = str(exc.value)
    assert "does not fit FLASH: overflowed by" in text and "1024 KB" in text and "\n" not in text
