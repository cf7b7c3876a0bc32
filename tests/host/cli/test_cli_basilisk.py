"""`staregen basilisk`: end to end on short runs, and every bad input one line, exit 2, nothing built."""
from __future__ import annotations

import json
import shutil

import pytest

from firmware import x86
from host.sim import basilisk
from tests.host.cli.package_inputs import cli
from tests.tools.test_package_lib import _resealed


def test_fig2_in_basilisk_with_the_cross_check(flight_package, tmp_path, capsys):
    out = tmp_path / "fly"
    code, stdout, err = cli(capsys, "basilisk", "--package", flight_package, "--controller", "fig2",
                            "--duration", "12", "--errors", "off", "--compare", "--out", out)
    assert code == 0, err
    metrics = json.loads((out / "metrics.json").read_text())
    assert metrics["scenario"]["simulator"] == f"Basilisk {basilisk.BSK_VERSION}"
    assert metrics["scenario"]["disturbances"] == ["gravity gradient", "drag", "magnetic"]
    assert metrics["simulation"]["sensor_errors"] is False and metrics["J_A"] > 0
    check = json.loads((out / "crosscheck.json").read_text())
    assert check["per_target_within_2_percent"] is True
    assert check["max_relative_difference"]["J_A"] < 0.02 and check["max_attitude_diff_deg"] < 1e-5
    for name in ("history.npz", "euler_error.png", "rate_error.png", "crosscheck_overlay.png"):
        assert (out / name).stat().st_size > 0
    assert "cross-check, Basilisk against staregen's simulator" in stdout and "within" in stdout
    assert check["kind"] == "staring" and check["disturbances"] == ["gravity gradient", "drag", "magnetic"]
    # the report's section: the table row and the overlay plot
    code, _, err = cli(capsys, "report", "--basilisk", out, "--out", tmp_path / "report")
    assert code == 0, err
    md = (tmp_path / "report" / "report.md").read_text()
    assert "The flight package in Basilisk, beside staregen's simulator" in md
    assert f"| fig2 | off | gravity gradient, drag, magnetic | 1 | {check['targets'][0]['staregen']['J_A']:.7g} / " in md
    assert "(basilisk1_crosscheck_overlay.png)" in md and (tmp_path / "report" / "basilisk1_crosscheck_overlay.png").exists()
    (out / "crosscheck.json").write_text(json.dumps({**check, "kind": "ramp"}))
    code, _, err = cli(capsys, "report", "--basilisk", out, "--out", tmp_path / "report2")
    assert code == 2 and "kind: expected 'staring' or 'tanh', got 'ramp'" in err and len(err.strip().splitlines()) == 1


def test_tanh_in_basilisk_with_the_cross_check(flight_package, tmp_path, capsys):
    out = tmp_path / "tanh"
    code, stdout, err = cli(capsys, "basilisk", "--package", flight_package, "--controller", "tanh",
                            "--duration", "25", "--dt", "0.005", "--compare", "--out", out)
    assert code == 0, err
    m = json.loads((out / "metrics.json").read_text())
    assert m["torque_within_bound"] is True and m["torque_bound"] == 4.5
    assert m["crosscheck"]["within"] is True and abs(m["crosscheck"]["relative_difference"]) < 0.05
    assert (out / "crosscheck_overlay.png").stat().st_size > 0
    check = json.loads((out / "crosscheck.json").read_text())
    assert check["kind"] == "tanh" and check["within"] is True
    code, _, err = cli(capsys, "report", "--basilisk", out, "--out", tmp_path / "report")
    assert code == 0, err
    assert "Paper 000's tanh law: settling time" in (tmp_path / "report" / "report.md").read_text()


def _one_line_error(capsys, *argv) -> str:
    code, stdout, err = cli(capsys, "basilisk", *argv)
    assert code == 2 and stdout == "" and len(err.strip().splitlines()) == 1, (code, stdout, err)
    return err


@pytest.mark.parametrize("argv, message", [
    (["--controller", "lqr"], "unknown controller 'lqr' for basilisk (one of: fig2, pid, tanh)"),
    (["--controller", "fig2", "--dt", "0.01"], "--dt applies to --controller tanh only"),
    (["--controller", "tanh", "--target", "all"], "--target does not apply to --controller tanh"),
    (["--controller", "pid"], "its controller flies its network; for --controller pid generate one with"),
    (["--duration", "-1"], "--duration"),
    (["--target", "500,0"], "target"),
    (["--disturbances", "gravity-gradient,solar"], "--disturbances: unknown 'solar'"),
    (["--controller", "tanh", "--disturbances", "none"], "--disturbances does not apply to --controller tanh"),
])
def test_bad_arguments(flight_package, tmp_path, capsys, argv, message):
    err = _one_line_error(capsys, "--package", flight_package, *argv, "--out", tmp_path / "o")
    assert message in err
    assert not (tmp_path / "o").exists()


def test_a_package_that_fails_its_check_is_never_loaded(flight_package, tmp_path, capsys, monkeypatch):
    folder = tmp_path / "pkg"
    shutil.copytree(flight_package, folder)
    (folder / "src" / "stare.c").write_text("int main(void) { return 0; }\n")
    monkeypatch.setattr(x86, "build", lambda *a, **k: pytest.fail("an edited package was compiled"))
    err = _one_line_error(capsys, "--package", folder, "--out", tmp_path / "o")
    assert "fails its check, not loaded: edited file: src/stare.c" in err


@pytest.mark.parametrize("edit", [lambda d: d.pop("config"), lambda d: d["config"]["timing"].update(control_period="0.1"),
                                  lambda d: d["config"]["timing"].update(control_period=True)])
def test_a_manifest_without_a_usable_period_is_one_line(flight_package, tmp_path, capsys, edit):
    folder = tmp_path / "pkg"
    shutil.copytree(flight_package, folder)
    _resealed(folder, edit_manifest=edit)
    err = _one_line_error(capsys, "--package", folder, "--controller", "tanh", "--out", tmp_path / "o")
    assert "config.timing.control_period is not a period" in err


def test_an_unsigned_package_under_a_key_is_never_loaded(flight_package, tmp_path, capsys, monkeypatch):
    key = tmp_path / "key.bin"
    key.write_bytes(bytes(range(32)))
    monkeypatch.setattr(x86, "build", lambda *a, **k: pytest.fail("an unverified package was compiled"))
    err = _one_line_error(capsys, "--package", flight_package, "--verify-key", key, "--out", tmp_path / "o")
    assert "fails its check, not loaded: signature: the manifest is not signed" in err


def test_a_missing_extra_is_one_line(flight_package, tmp_path, capsys, monkeypatch):
    monkeypatch.setattr(basilisk, "_loaded", None)
    monkeypatch.setitem(basilisk._MODULES, "spacecraft", "Basilisk.simulation.no_such_module")
    monkeypatch.setattr(x86, "build", lambda *a, **k: pytest.fail("built without Basilisk"))
    err = _one_line_error(capsys, "--package", flight_package, "--out", tmp_path / "o")
    assert "Basilisk is not installed (the optional extra `basilisk`: pip install -e '.[basilisk]')" in err


def test_a_missing_package_folder_is_one_line(tmp_path, capsys):
    assert "no such folder" in _one_line_error(capsys, "--package", tmp_path / "none", "--out", tmp_path / "o")
