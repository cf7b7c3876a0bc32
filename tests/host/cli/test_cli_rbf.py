"""`staregen simulate --controller rbf|rbf-c` on paper 002's scenario from the command line."""
from __future__ import annotations

import json

from tests.host.cli.package_inputs import cli


def test_simulate_rbf_prints_the_papers_figures_beside_ours(tmp_path, capsys):
    out = tmp_path / "s"
    code, stdout, err = cli(capsys, "simulate", "--controller", "rbf-c", "--params", "docs/rbf_paper002_theorem1.toml",
                            "--duration", "3", "--out", str(out))
    assert code == 0, err
    assert "theorem 1, T = 0.1 s, 3 s, SIL x86" in stdout and "(paper: 22.9 s)" in stdout and "(paper: 5.7 s)" in stdout
    assert "golden mismatches 0 steps" in stdout
    metrics = json.loads((out / "metrics.json").read_text())
    assert metrics["controller"] == "rbf-c" and metrics["golden_mismatch_steps"] == 0
    assert (out / "fig_c_vs_float64.png").exists()


def test_an_explicit_duration_equal_to_another_default_is_honoured(tmp_path, capsys):
    """`--duration 100.0` once read as 'not given' (the pid default's text) and ran rbf's 1,000 s."""
    code, stdout, err = cli(capsys, "simulate", "--controller", "rbf", "--duration", "100.0", "--period", "1",
                            "--dt", "1", "--out", str(tmp_path / "s"))
    assert code == 0, err
    assert "theorem 2, T = 1 s, 100 s" in stdout
    assert json.loads((tmp_path / "s" / "metrics.json").read_text())["duration"] == 100.0
