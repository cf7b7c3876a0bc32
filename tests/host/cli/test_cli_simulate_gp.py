"""`staregen simulate --controller gp-baseline|gp`: paper 004's takeover from the command line (short
runs of the trained M = 20 model in docs/)."""
from __future__ import annotations

import json

import numpy as np

from tests.host.cli.package_inputs import cli


def test_simulate_gp_writes_metrics_history_and_the_papers_figures(tmp_path, capsys):
    out = tmp_path / "gp"
    code, stdout, err = cli(capsys, "simulate", "--controller", "gp", "--duration", "12", "--start", "outside",
                            "--out", str(out))
    assert code == 0, err
    m = json.loads((out / "metrics.json").read_text())
    assert (m["controller"], m["start"], m["duration"], m["n_inducing"]) == ("gp", "outside", 12.0, 20)
    assert m["params"].endswith("gp_paper004.toml")
    names = {p.name for p in out.iterdir()}
    assert {"fig4_attitude.png", "fig5_rates.png", "fig6_torque.png", "fig7_variance_gains.png",
            "fig_gp_mean.png", "history.npz"} <= names
    h = np.load(out / "history.npz")
    assert h["t"][-1] == 12.0 and h["gains"].shape == (121, 2)
    assert "variance fraction s first / last 60 s" in stdout and "gp: paper 004 takeover, start outside" in stdout


def test_simulate_gp_baseline_has_no_gp_figures_and_constant_gains(tmp_path, capsys):
    out = tmp_path / "b"
    code, stdout, err = cli(capsys, "simulate", "--controller", "gp-baseline", "--duration", "5",
                            "--params", "docs/gp_paper004.toml", "--out", str(out))
    assert code == 0, err
    m = json.loads((out / "metrics.json").read_text())
    assert m["start"] == "capture" and m["gains_first_60s"] == [4.0, 72.0] and m["var_fraction_first_60s"] is None
    assert not (out / "fig7_variance_gains.png").exists()
    assert "variance fraction" not in stdout
