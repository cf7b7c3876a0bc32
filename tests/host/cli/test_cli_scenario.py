"""`staregen scenario list|init|check|seal`: happy paths, and every bad file of the scenario-file
corpus refused with exit 2, exactly one line on stderr and no traceback."""
from __future__ import annotations

import pytest

from host.cli import main
from host.core.constants import ARCSEC
from host.sim import scenario_file as sf
from tests.host.sim.test_scenario_file import BAD_FILES, VALID_BODY, write_bad


def run(capsys, *argv: str) -> tuple[int, str, str]:
    code = main(list(argv))
    out, err = capsys.readouterr()
    return code, out, err


def assert_refused(code: int, out: str, err: str, *words: str) -> None:
    assert code == 2
    assert len(err.splitlines()) == 1, err
    assert err.startswith("staregen scenario: error: "), err
    assert "Traceback" not in err and out == ""
    for word in words:
        assert word in err, err


def test_init_writes_the_default_reading(tmp_path, capsys):
    """Without --reading: the commands' default, the calibration study's choice (not table6)."""
    path = tmp_path / "default.toml"
    code, out, err = run(capsys, "scenario", "init", "--out", str(path))
    assert code == 0 and err == ""
    scenario = sf.load(path)
    assert scenario.reading == sf.DEFAULT_READING != "table6" and scenario.sha256 == sf.default_scenario().sha256


def test_list_names_table6(capsys):
    code, out, err = run(capsys, "scenario", "list")
    assert code == 0 and err == ""
    assert out.startswith("table6: ") and "3σ" in out


def test_init_check_seal(tmp_path, capsys):
    path = tmp_path / "scenario.toml"
    code, out, err = run(capsys, "scenario", "init", "--reading", "table6", "--out", str(path))
    assert code == 0 and err == "" and path.is_file()
    code, out, err = run(capsys, "scenario", "check", str(path))
    assert code == 0 and err == ""
    assert "reading table6" in out and "sha256 " in out
    # the star sensor's σ in rad: 3″ stated as 3σ is 1″ per axis
    assert f"{ARCSEC:.6g}" in out and "rad/s" in out and "N*m" in out
    code, out, err = run(capsys, "scenario", "seal", str(path))
    assert code == 0 and "seal already current" in out

    text = path.read_text(encoding="utf-8")
    path.write_text(text.replace("random_arcsec = [3.0, 3.0, 3.0]", "random_arcsec = [6.0, 6.0, 6.0]"), encoding="utf-8")
    assert_refused(*run(capsys, "scenario", "check", str(path)), "sha256", "staregen scenario seal")
    code, out, err = run(capsys, "scenario", "seal", str(path))
    assert code == 0 and "sealed" in out and err == ""
    code, out, err = run(capsys, "scenario", "check", str(path))
    assert code == 0 and f"{2 * ARCSEC:.6g}" in out


def test_init_refuses_an_existing_file(tmp_path, capsys):
    path = tmp_path / "scenario.toml"
    path.write_text("mine\n", encoding="utf-8")
    assert_refused(*run(capsys, "scenario", "init", "--out", str(path)), "--force")
    assert path.read_text(encoding="utf-8") == "mine\n"
    code, out, err = run(capsys, "scenario", "init", "--out", str(path), "--force")
    assert code == 0 and path.read_text(encoding="utf-8").startswith("# staregen scenario")


def test_init_refuses_unknown_reading_and_a_directory(tmp_path, capsys):
    assert_refused(*run(capsys, "scenario", "init", "--reading", "table7", "--out", str(tmp_path / "s.toml")),
                   "table7", "table6")
    assert not (tmp_path / "s.toml").exists()
    assert_refused(*run(capsys, "scenario", "init", "--out", str(tmp_path), "--force"), "directory")


def test_check_missing_file(tmp_path, capsys):
    assert_refused(*run(capsys, "scenario", "check", str(tmp_path / "none.toml")), "none.toml")


def test_check_unsealed_hand_written_file(tmp_path, capsys):
    path = tmp_path / "s.toml"
    path.write_text(VALID_BODY, encoding="utf-8")
    assert_refused(*run(capsys, "scenario", "check", str(path)), "sha256", "staregen scenario seal")


@pytest.mark.parametrize("name, edit, key", BAD_FILES, ids=[c[0] for c in BAD_FILES])
def test_check_bad_file(tmp_path, capsys, name, edit, key):
    path = write_bad(tmp_path, edit)
    before = path.read_bytes()
    assert_refused(*run(capsys, "scenario", "check", str(path)), str(path), key)
    assert_refused(*run(capsys, "scenario", "seal", str(path)), str(path), key)
    assert path.read_bytes() == before
