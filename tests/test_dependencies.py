"""The pinned learning stack: gpytorch (paper 004's GP training) installs on the torch the project pins
and does not replace it (any other torch would pull gigabytes of CUDA packages)."""
from __future__ import annotations

import tomllib
from importlib import metadata
from pathlib import Path

import gpytorch
import torch

PYPROJECT = tomllib.loads((Path(__file__).resolve().parents[1] / "pyproject.toml").read_text())


def _pin(name: str) -> str:
    pins = [d for d in PYPROJECT["project"]["dependencies"] if d.split("==")[0].strip() == name]
    assert len(pins) == 1 and "==" in pins[0], pins
    return pins[0].split("==")[1].strip()


def test_torch_is_the_pinned_cpu_build_and_gpytorch_runs_on_it():
    assert metadata.version("torch").split("+")[0] == _pin("torch") == "2.13.0"
    assert metadata.version("gpytorch") == _pin("gpytorch")
    assert not torch.cuda.is_available()
    with torch.no_grad():
        k = gpytorch.kernels.RBFKernel()(torch.zeros(1, 2), torch.zeros(1, 2)).to_dense()
    assert float(k[0, 0]) == 1.0          # exp(0): the squared-exponential kernel at zero distance


def test_the_basilisk_extra_is_pinned_and_installed_by_make_test():
    """Issue 28: `make test` installs the optional extra `basilisk` (bsk pinned); `make run` does not need it."""
    extra = PYPROJECT["project"]["optional-dependencies"]["basilisk"]
    assert extra == ["bsk==2.12.1"]
    assert metadata.version("bsk") == "2.12.1"
    root = Path(__file__).resolve().parents[1]
    makefile = (root / "Makefile").read_text()
    assert "test: setup-test\n" in makefile and "\t@bash tools/setup.sh test\n" in makefile
    assert 'extras="dev,basilisk"' in (root / "tools" / "setup.sh").read_text()
