"""What the package tests of the command line share: running `staregen` in-process, and the inputs
of `generate` (a default configuration and a 12-40-3 network)."""
from __future__ import annotations

from pathlib import Path

from codegen.artifact import random_artifact
from host.cli import main


def cli(capsys, *argv):
    """(exit code, stdout, stderr) of `staregen argv...`."""
    code = main([str(a) for a in argv])
    out, err = capsys.readouterr()
    return code, out, err


def package_inputs(folder: Path) -> tuple[Path, Path]:
    """controller.toml (defaults) and network.json (a random 12-40-3 artifact) written into `folder`."""
    cfg, net = folder / "controller.toml", folder / "network.json"
    assert main(["config", "init", "--out", str(cfg)]) == 0
    random_artifact((12, 40, 3), seed=2).save(net)
    return cfg, net
