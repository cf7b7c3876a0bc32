"""`staregen config`, `generate` and `package check` from the command line: defaults, one-line
errors with exit 2 and no partial package, a package that checks out, and an edited one that does not."""
from __future__ import annotations

import pytest

from tests.host.cli.package_inputs import cli, package_inputs

SMALL = ["--gate-vectors", "1000", "--vectors", "32", "--cycles-per-class", "3"]


@pytest.fixture()
def inputs(tmp_path):
    return package_inputs(tmp_path)


def test_config_init_check_seal(tmp_path, capsys, inputs):
    cfg, _ = inputs
    code, out, err = cli(capsys, "config", "init", "--out", str(cfg))
    assert code == 2 and "exists; use --force" in err and err.count("\n") == 1
    code, out, _ = cli(capsys, "config", "check", str(cfg))
    assert code == 0 and "Kp [17.0, 54.0, 18.0]" in out
    cfg.write_text(cfg.read_text().replace("dwell_steps = 10", "dwell_steps = 12"))
    code, _, err = cli(capsys, "config", "check", str(cfg))
    assert code == 2 and "sha256: mismatch" in err and err.count("\n") == 1
    code, out, _ = cli(capsys, "config", "seal", str(cfg))
    assert code == 0 and "sealed" in out
    assert cli(capsys, "config", "check", str(cfg))[0] == 0


BAD_CONFIG = [
    ("dwell_steps = 10", "", "timing.dwell_steps: missing key"),
    ("[limits]", "[limits]\nspeed = 1.0", "limits.speed: unknown key"),
    ("kp = [17.0, 54.0, 18.0]", "kp = [17.0, -54.0, 18.0]", "pid.kp[1]: a gain must not be negative"),
    ("control_period = 0.1", "control_period = 0.0", "timing.control_period: must be in (0, 10] s"),
    ("dwell_steps = 10", "dwell_steps = 0", "timing.dwell_steps: must be in [1,"),
    ("torque_limit = 1.0", "torque_limit = -1.0", "limits.torque_limit: must be > 0"),
    ("version = 1", "version = 3", "version: unsupported version 3"),
]


@pytest.mark.parametrize("old, new, message", BAD_CONFIG, ids=[m for *_, m in BAD_CONFIG])
def test_bad_configuration_gives_one_line_and_no_package(tmp_path, capsys, inputs, old, new, message):
    cfg, net = inputs
    cfg.write_text(cfg.read_text().replace(old, new))
    out = tmp_path / "pkg"
    code, stdout, err = cli(capsys, "generate", "--config", str(cfg), "--network", str(net), "--out", str(out), *SMALL)
    assert code == 2 and err.count("\n") == 1 and message in err and "Traceback" not in err, err
    assert not out.exists() and [p.name for p in tmp_path.iterdir() if "pkg" in p.name] == []


def test_tanh_file_must_match_the_configuration(tmp_path, capsys, inputs):
    cfg, net = inputs
    code, _, err = cli(capsys, "generate", "--config", str(cfg), "--network", str(net), "--tanh",
                       "docs/tanh_paper000.toml", "--out", str(tmp_path / "pkg"), *SMALL)
    assert code == 2 and "do not include \"tanh\"" in err


def test_a_configured_unit_without_its_parameter_file_is_one_line(tmp_path, capsys, inputs):
    cfg, net = inputs
    cfg.write_text(cfg.read_text().replace('units = ["controller"]', 'units = ["controller", "tanh"]'))
    assert cli(capsys, "config", "seal", str(cfg))[0] == 0
    out = tmp_path / "pkg"
    code, _, err = cli(capsys, "generate", "--config", str(cfg), "--network", str(net), "--out", str(out), *SMALL)
    assert code == 2 and err.count("\n") == 1
    assert "units include \"tanh\": give its parameter file with --params tanh=FILE" in err
    assert not out.exists()


def test_generate_then_check(tmp_path, capsys, inputs):
    cfg, net = inputs
    out = tmp_path / "pkg"
    code, stdout, err = cli(capsys, "generate", "--config", str(cfg), "--network", str(net), "--out", str(out), *SMALL)
    assert code == 0, err
    assert "self-test on x86: 0 mismatching words" in stdout and "self-test on arm: 0" in stdout
    assert "whole step worst case" in stdout
    code, stdout, _ = cli(capsys, "package", "check", str(out), "--run", "x86")
    assert code == 0 and "match the manifest" in stdout and "x86: self-test 0" in stdout
    (out / "ICD.md").write_text((out / "ICD.md").read_text() + "edited\n")
    code, stdout, _ = cli(capsys, "package", "check", str(out))
    assert code == 1 and stdout.strip() == f"{out}: edited file: ICD.md (sha256 differs from the manifest)"
    code, _, err = cli(capsys, "package", "check", str(out), "--run", "riscv")
    assert code == 2 and "unknown target 'riscv'" in err
    code, _, err = cli(capsys, "package", "check", str(tmp_path))
    assert code == 2 and "manifest.json: missing" in err
