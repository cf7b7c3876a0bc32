"""The controller configuration artifact: defaults from the paper, strict schema, seal, one-line errors."""
from __future__ import annotations

import re
import tomllib

import pytest

from codegen.package import config as pc
from host.control.nn_controller import CONFIG_SOURCES, default_package_config


@pytest.fixture()
def default_file(tmp_path):
    return pc.write(default_package_config(), tmp_path / "controller.toml", CONFIG_SOURCES)


def test_defaults_reproduce_table1_and_table6(default_file):
    cfg = pc.load(default_file)
    c = cfg.controller
    # paper 001 Table 1 (N·m/°, N·m/(°·s), N·m/(°/s)) and Table 6 (1 N·m per wheel), typed from the paper
    assert c.kp == (17.0, 54.0, 18.0)
    assert c.ki == (0.0, 0.0, 0.0)
    assert c.kd == (46.0, 77.0, 50.0)
    assert c.torque_limit == 1.0
    assert c.control_period == 0.1
    assert c.earth_a == 6378137.0 and abs(c.earth_e2 - 0.00669437999014) < 1e-14
    assert cfg.units == ("controller",) and cfg.name == "stare"


def test_round_trip_and_comments(default_file):
    text = default_file.read_text()
    assert "# from: paper 001 Table 1" in text and "Table 6" in text
    assert pc.load(default_file) == default_package_config()


def test_seal_covers_values_not_layout(default_file):
    text = default_file.read_text()
    default_file.write_text(text.replace("# N*m/deg", "# a comment changed").replace("kp = [", "kp  =  ["))
    pc.load(default_file)                                   # layout and comments: still valid
    default_file.write_text(text.replace("kp = [17.0, 54.0, 18.0]", "kp = [17.0, 55.0, 18.0]"))
    with pytest.raises(pc.ConfigError, match=r"sha256: mismatch.*staregen config seal"):
        pc.load(default_file)
    digest, changed = pc.seal(default_file)
    assert changed and pc.load(default_file).controller.kp == (17.0, 55.0, 18.0)
    assert digest == pc.load(default_file).sha256 != default_package_config().sha256
    assert pc.seal(default_file) == (digest, False)


def test_integers_and_reals_hash_alike(default_file):
    text = default_file.read_text().replace("kp = [17.0, 54.0, 18.0]", "kp = [17, 54, 18]")
    assert tomllib.loads(text)["pid"]["kp"] == [17, 54, 18]
    default_file.write_text(text)
    assert pc.load(default_file).controller.kp == (17.0, 54.0, 18.0)      # seal unchanged


BAD = [
    (lambda t: t.replace('dwell_steps = 10', ''), r"timing\.dwell_steps: missing key"),
    (lambda t: t.replace('[limits]', '[limits]\nspeed = 3'), r"limits\.speed: unknown key"),
    (lambda t: t + "\n[extra]\n", r"extra: unknown key"),
    (lambda t: t.replace('kd = [46.0, 77.0, 50.0]', 'kd = [46.0, -77.0, 50.0]'), r"pid\.kd\[1\]: .*not be negative"),
    (lambda t: t.replace('kp = [17.0, 54.0, 18.0]', 'kp = [17.0, 54.0]'), r"pid\.kp: must be a list of 3"),
    (lambda t: t.replace('control_period = 0.1', 'control_period = 0.0'), r"timing\.control_period: must be in"),
    (lambda t: t.replace('control_period = 0.1', 'control_period = -1.0'), r"timing\.control_period"),
    (lambda t: t.replace('dwell_steps = 10', 'dwell_steps = 0'), r"timing\.dwell_steps: must be in \[1"),
    (lambda t: t.replace('dwell_steps = 10', 'dwell_steps = 2.5'), r"timing\.dwell_steps: must be an integer"),
    (lambda t: t.replace('torque_limit = 1.0', 'torque_limit = 0.0'), r"limits\.torque_limit: must be > 0"),
    (lambda t: t.replace('torque_limit = 1.0', 'torque_limit = inf'), r"limits\.torque_limit: must be finite"),
    (lambda t: t.replace('torque_limit = 1.0', 'torque_limit = "1"'), r"limits\.torque_limit: must be a number"),
    (lambda t: t.replace('version = 1', 'version = 2'), r"version: unsupported version 2"),
    (lambda t: t.replace('version = 1', 'version = 1.0'), r"version: must be the integer 1"),
    (lambda t: t.replace('name = "stare"', 'name = "Stare*/"'), r"package\.name: must be a lower-case C identifier"),
    (lambda t: t.replace('name = "stare"', 'name = "sg_x"'), r"package\.name"),
    (lambda t: t.replace('units = ["controller"]', 'units = ["tanh"]'), r"package\.units: must include"),
    (lambda t: t.replace('units = ["controller"]', 'units = ["controller", "pid"]'), r"package\.units: unknown unit"),
    (lambda t: t.replace('e2 = ', 'e2 = 1.5 #'), r"earth\.e2: must be in \[0, 1\)"),
    (lambda t: t.replace('[timing]', '[timing]\ncontrol_period = 0.2'), r"not valid TOML"),   # duplicate key
    (lambda t: t.replace('format = "staregen.controller-config"', 'format = "x"'), r"format: must be"),
    (lambda t: re.sub(r'sha256 = "[0-9a-f]+"', 'sha256 = "abc"', t), r"sha256: missing or not 64"),
]


@pytest.mark.parametrize("edit, message", BAD, ids=[m for _, m in BAD])
def test_bad_configuration_is_one_line_naming_the_key(default_file, edit, message):
    default_file.write_text(edit(default_file.read_text()))
    with pytest.raises(pc.ConfigError) as exc:
        pc.load(default_file)
    text = str(exc.value)
    assert "\n" not in text and text.startswith(str(default_file))
    assert re.search(message, text), text


def test_unreadable_and_binary_files(tmp_path):
    with pytest.raises(pc.ConfigError, match="cannot read"):
        pc.load(tmp_path / "missing.toml")
    (tmp_path / "bin.toml").write_bytes(b"\xff\xfe\x00")
    with pytest.raises(pc.ConfigError, match="not UTF-8"):
        pc.load(tmp_path / "bin.toml")
