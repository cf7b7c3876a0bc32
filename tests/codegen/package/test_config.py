"""The controller configuration artifact: defaults from the paper, strict schema, seal, one-line errors."""
from __future__ import annotations

import os
import re
import threading
import tomllib

import pytest

from codegen import names, reading
from codegen.cgen import check_name
from codegen.package import config as pc
from firmware.errors import FirmwareError
from firmware.package_build import build_image
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
    # issue 25: ranges hold for the float32 the C holds, not only for the file's float64
    (lambda t: t.replace('torque_limit = 1.0', 'torque_limit = 1e-50'), r"limits\.torque_limit: 1e-50 rounds to 0"),
    (lambda t: t.replace('integral_limit = 100.0', 'integral_limit = 1e-50'), r"pid\.integral_limit: 1e-50 rounds to 0"),
    (lambda t: t.replace('control_period = 0.1', 'control_period = 1e-50'), r"timing\.control_period: 1e-50 rounds"),
    (lambda t: t.replace('torque_limit = 1.0', 'torque_limit = 1e-40'), r"torque_limit: 1e-40 rounds to a subnormal"),
    (lambda t: t.replace('kp = [17.0, 54.0, 18.0]', 'kp = [17.0, 1e-50, 18.0]'), r"pid\.kp\[1\]: 1e-50 rounds to 0"),
    (lambda t: t.replace('e2 = ', 'e2 = 0.9999999999999999 #'), r"earth\.e2: must be in \[0, 1\).*as float32: 1\.0"),
    (lambda t: t.replace('mu = ', 'mu = 3.4028236e38 #'), r"earth\.mu: must be finite \(and within float32\)"),
    # issue 25: integers of hundreds (or thousands) of digits are one line, not an OverflowError / ValueError
    (lambda t: t.replace('torque_limit = 1.0', 'torque_limit = ' + '9' * 400), r"limits\.torque_limit: must be finite"),
    (lambda t: t.replace('dwell_steps = 10', 'dwell_steps = ' + '9' * 400), r"timing\.dwell_steps: must be in \[1"),
    (lambda t: t.replace('torque_limit = 1.0', 'torque_limit = ' + '9' * 5000), r"not valid TOML"),
    # issue 25: one number grammar for files (no TOML underscores or 0x/0o/0b, no booleans)
    (lambda t: t.replace('torque_limit = 1.0', 'torque_limit = 1_0.0'), r"line \d+: number '1_0\.0'"),
    (lambda t: t.replace('dwell_steps = 10', 'dwell_steps = 0xa'), r"number '0xa'"),
    (lambda t: t.replace('kp = [17.0, 54.0, 18.0]', 'kp = [17.0, +5_4.0, 18.0]'), r"number '\+5_4\.0'"),
    (lambda t: t.replace('dwell_steps = 10', 'dwell_steps = true'), r"timing\.dwell_steps: must be an integer"),
    (lambda t: t.replace('torque_limit = 1.0', 'torque_limit = true'), r"limits\.torque_limit: must be a number"),
    # issue 25: one name rule; every name derived from an accepted one is valid too
    (lambda t: t.replace('name = "stare"', 'name = "sg"'), r"package\.name: must not be 'sg'"),
    (lambda t: t.replace('name = "stare"', 'name = "image"'), r"package\.name: must not be a CMake-reserved"),
    (lambda t: t.replace('name = "stare"', 'name = "all"'), r"package\.name: must not be a CMake-reserved"),
    (lambda t: t.replace('name = "stare"', 'name = "int"'), r"package\.name: must not be a C keyword"),
    (lambda t: t.replace('name = "stare"', 'name = "stdint"'), r"package\.name: must not be the name of a C standard"),
    (lambda t: t.replace('name = "stare"', 'name = "harness"'), r"package\.name: must not be the name"),
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


def test_underscores_in_keys_strings_and_comments_are_not_numbers(default_file):
    """The number grammar looks at numbers only: keys (torque_limit), strings and comments keep their '_'."""
    text = default_file.read_text().replace("# N*m/deg", "# 1_000 in a comment")
    default_file.write_text(text)
    assert pc.load(default_file).controller.torque_limit == 1.0


def test_float32_rule_accepts_the_edges_that_survive_rounding(default_file):
    """Values that stay in range after rounding pass: the largest float32 below 1 for e2, the
    smallest normal float32 for a positive limit (then re-sealed)."""
    text = default_file.read_text()
    text = text.replace("e2 = ", "e2 = 0.99999994 #").replace("torque_limit = 1.0", "torque_limit = 1.1754944e-38")
    default_file.write_text(text)
    pc.seal(default_file)
    c = pc.load(default_file).controller
    assert c.earth_e2 == 0.99999994 and c.torque_limit == 1.1754944e-38


def _error_of(read, path) -> str:
    try:
        read(path)
    except pc.ConfigError as exc:
        return str(exc)
    return "(no error)"


def test_a_folder_is_not_read(tmp_path):
    for read in (pc.load, pc.seal):
        assert _error_of(read, tmp_path) == f"{tmp_path}: cannot read (not a regular file)"


def test_a_fifo_is_refused_without_waiting_for_a_writer(tmp_path):
    """Opening a FIFO for reading blocks until a writer comes (and /dev/zero never ends): only
    regular files are read. The read runs in a thread; a blocked one is released by opening
    the FIFO's write end, so the test fails instead of hanging."""
    path = tmp_path / "controller.toml"
    os.mkfifo(path)
    for read in (pc.load, pc.seal):
        result = {}
        worker = threading.Thread(target=lambda: result.update(error=_error_of(read, path)), daemon=True)
        worker.start()
        worker.join(5.0)
        if worker.is_alive():
            os.close(os.open(path, os.O_WRONLY | os.O_NONBLOCK))   # the reader gets EOF
            worker.join(5.0)
        assert result.get("error") == f"{path}: cannot read (not a regular file)"


def test_reads_are_capped_by_the_bytes_read(default_file):
    """A file over the cap is refused after reading cap + 1 bytes (not by trusting st_size)."""
    default_file.write_text(default_file.read_text() + "#" * reading.MAX_TEXT_BYTES)
    with pytest.raises(pc.ConfigError, match=f"larger than {reading.MAX_TEXT_BYTES} bytes"):
        pc.load(default_file)


def test_every_name_config_accepts_generates_valid_entries(tmp_path):
    """Whatever the configuration accepts, every emitter and the package build accept too."""
    for name in ("a", "stare", "sgp", "x_nn", "abcdefghijkl", "image2", "s", "tanh", "nn"):
        cfg = default_package_config(name)
        assert cfg.name == name
        for ident in (name, *(name + s for s in names.DERIVED_SUFFIXES)):
            assert check_name(ident) == ident
    for name in ("sg", "sg_x", "image", "int", "stdint", "all", "abcdefghijklm", "1a", "A"):
        with pytest.raises(pc.ConfigError):
            default_package_config(name)
        with pytest.raises(FirmwareError, match="package name"):     # the test image's build: the same rule
            build_image(tmp_path, name, "x86", tmp_path / "build")
