"""`staregen simulate`: bad input gives one line, exit 2, no traceback and no output; a short run
writes metrics.json (J_A, J_w, J), the history and the plots."""
import json
import subprocess
import sys

import numpy as np
import pytest

from host.sim import campaign
from host.cli import main


def run_cli(capsys, *argv):
    code = main(["simulate", *argv])
    out, err = capsys.readouterr()
    return code, out, err


def leftovers(folder):
    """Anything the run left next to the output folder (temporary siblings included)."""
    return sorted(p.name for p in folder.parent.iterdir() if folder.name in p.name)


@pytest.mark.parametrize("argv, message", [
    (["--target", "mars"], "unknown target"),
    (["--target", "120,95"], "latitude"),
    (["--target", "120,-91"], "latitude"),
    (["--duration", "-5"], "positive"),
    (["--duration", "abc"], "number"),
    (["--duration", "nan"], "finite"),
    (["--seed", "-1"], "seed"),
    (["--controller", "nope"], "unknown controller"),
    (["--target", "0,0"], "below the horizon"),
    (["--duration", "5"], "no imaging window"),
])
def test_bad_input_is_one_line_with_no_output(tmp_path, capsys, argv, message):
    out = tmp_path / "run"
    code, stdout, err = run_cli(capsys, *argv, "--out", str(out))
    assert code == 2
    assert err.count("\n") == 1 and err.startswith("staregen simulate: error:") and message in err, err
    assert "Traceback" not in err and stdout == ""
    assert leftovers(out) == []


def test_unwritable_output_folder(tmp_path, capsys):
    blocker = tmp_path / "file"
    blocker.write_text("not a folder")
    for out in (blocker / "run", blocker):
        code, stdout, err = run_cli(capsys, "--duration", "12", "--out", str(out))
        assert code == 2 and err.count("\n") == 1 and "Traceback" not in err, err
    assert blocker.read_text() == "not a folder"


def test_a_foreign_folder_is_never_replaced(tmp_path, capsys):
    home = tmp_path / "home"
    home.mkdir()
    (home / "thesis.tex").write_text("precious")
    code, _, err = run_cli(capsys, "--duration", "12", "--out", str(home))
    assert code == 2 and "refusing" in err and err.count("\n") == 1
    assert (home / "thesis.tex").read_text() == "precious"


def test_failure_during_the_run_leaves_no_partial_output(tmp_path, capsys, monkeypatch):
    out = tmp_path / "run"
    out.mkdir()
    (out / "metrics.json").write_text('{"J": 1}')   # a previous run's output

    def broken_write(result, folder, scenario=None):
        (folder / "metrics.json").write_text("{half")
        raise OSError(28, "No space left on device")

    monkeypatch.setattr("host.cli.simulate.write_campaign", broken_write)
    code, _, err = run_cli(capsys, "--duration", "11", "--out", str(out))
    assert code == 2 and "No space left" in err and err.count("\n") == 1
    assert (out / "metrics.json").read_text() == '{"J": 1}'   # the previous output is intact
    assert sorted(p.name for p in out.iterdir()) == ["metrics.json"]
    assert leftovers(out) == ["run"]


def test_console_script_bad_target_has_no_traceback(tmp_path):
    # the console script `staregen` is this same call: sys.exit(host.cli.main())
    proc = subprocess.run([sys.executable, "-c", "import sys; from host.cli import main; sys.exit(main())",
                           "simulate", "--target", "nowhere",
                           "--out", str(tmp_path / "x")], capture_output=True, text=True)
    assert proc.returncode == 2 and proc.stderr.count("\n") == 1 and "Traceback" not in proc.stderr
    assert not (tmp_path / "x").exists()


def test_short_run_writes_metrics_history_and_plots(tmp_path, capsys):
    out = tmp_path / "run"
    code, stdout, err = run_cli(capsys, "--target", "central", "--duration", "12", "--seed", "2",
                                "--out", str(out))
    assert code == 0, err
    doc = json.loads((out / "metrics.json").read_text())
    for key in ("J_A", "J_w", "J"):
        assert np.isfinite(doc[key]) and doc[key] > 0
    assert doc["J"] == pytest.approx(doc["J_A"] + 5 * doc["J_w"])
    assert len(doc["targets"]) == 1 and doc["targets"][0]["J_A"] == doc["J_A"]
    assert doc["imaging"]["images_per_target"] == 2 and doc["simulation"]["seed"] == 2
    h = np.load(out / "history.npz")
    assert h["A_bd"].shape == (601, 3) and h["t"][-1] == pytest.approx(12.0)
    for png in ("euler_error.png", "rate_error.png"):
        assert (out / png).read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert "central" in stdout and f"{doc['J_A']:.3e}" in stdout


def test_several_targets_write_averages(tmp_path, capsys, monkeypatch):
    # two explicit targets through the campaign layer (the CLI 'all' runs the same code on 100)
    from host.sim.metrics import ImagingPlan
    from host.sim.simulator import SimConfig
    from host.sim.targets import central_target, staring_targets

    targets = [central_target(), staring_targets()[0]]
    r = campaign.run_campaign("pid", targets, SimConfig(duration=11.0), ImagingPlan(1.0, 10.0),
                              workers=1, progress=False)
    campaign.write_campaign(r, tmp_path)
    doc = json.loads((tmp_path / "metrics.json").read_text())
    assert doc["n_targets"] == 2
    assert doc["J_A"] == pytest.approx(np.mean([t["J_A"] for t in doc["targets"]]))
    assert doc["J_w"] == pytest.approx(np.mean([t["J_w"] for t in doc["targets"]]))
    assert np.load(tmp_path / "histories.npz")["A_bd"].shape == (2, 111, 3)
    assert (tmp_path / "targets_JA_Jw.png").exists()


def test_simulate_tanh_writes_the_issue7_metrics(tmp_path):
    import json

    from host.cli import main as cli_main

    out = tmp_path / "tanh"
    assert cli_main(["simulate", "--controller", "tanh", "--period", "0.1", "--duration", "3", "--out", str(out)]) == 0
    m = json.loads((out / "metrics.json").read_text())
    for key in ("t_settle", "e_final", "we_final", "u_max"):
        assert key in m
    assert 0 < m["u_max"] <= 4.5  # the tanh law bounds |u_i| by k1 + k2 + k3 = 4.5 N*m
    assert sorted(p.name for p in out.glob("fig*.png")) == [
        "fig5_attitude_error.png", "fig6_angular_velocity_error.png", "fig7_x2.png", "fig8_torque.png"]


def test_period_is_refused_for_the_staring_controllers(tmp_path, capsys):
    from host.cli import main as cli_main

    assert cli_main(["simulate", "--controller", "pid", "--period", "0.1", "--out", str(tmp_path / "o")]) == 2
    assert "--period" in capsys.readouterr().err
    assert not (tmp_path / "o").exists()
