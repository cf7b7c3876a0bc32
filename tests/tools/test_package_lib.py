"""tools.package_lib: a checked package linked through its public API, bit for bit the unit's C; a
package that fails its check is never compiled, one whose self-test fails is refused."""
from __future__ import annotations

import json
import re
import shutil

import numpy as np
import pytest

from codegen.package import manifest
from codegen.unit import words
from codegen.units.controller import spec as cs
from host.control.nn_controller import flight_config, load_artifact
from host.control.package_controller import CONTROLLER_RECORDS, TANH_RECORDS
from codegen.units.controller.unit import ControllerUnit
from firmware import x86
from host.sim.scenarios import unit_inputs
from tools.errors import ToolError
from tools.package_lib import Records, load_package
from tools.runners import runner


def test_the_package_steps_bit_for_bit_as_the_units_own_build(flight_package):
    """The same records through the package's stare_step and through the unit's x86 runner (its golden
    model's twin in the gate): identical output and state words, step after step."""
    pkg = load_package(flight_package)
    entry = pkg.entry("controller", CONTROLLER_RECORDS)
    unit = ControllerUnit(load_artifact(None), flight_config(), scenario=unit_inputs("controller")["scenario"])
    records = unit.gate_sequences(1, 300, 0)[0]          # a closed-loop staring sequence, network and PID
    want = runner(unit, "x86").sequence(records)
    got = np.concatenate([entry.step(r) for r in records])
    assert np.array_equal(words(got), words(want))
    assert len({tuple(t) for t in got["torque"]}) > 100     # the records exercise the law, not one constant
    assert (got["status"] & cs.STATUS_PID == 0).any()   # the network branch flew


def test_init_resets_the_state(flight_package):
    entry = load_package(flight_package).entry("tanh", TANH_RECORDS)
    rec = np.zeros(1, TANH_RECORDS.input)
    rec["R_c"] = np.eye(3).ravel()
    rec["R_t"] = np.array([[0, -1, 0], [1, 0, 0], [0, 0, 1]], np.float32).ravel()
    first = entry.step(rec)
    second = entry.step(rec)
    assert not np.array_equal(words(first), words(second))      # varpi moved
    entry.init()
    assert np.array_equal(words(entry.step(rec)), words(first))


def test_a_package_that_fails_its_check_is_never_compiled(flight_package, tmp_path, monkeypatch):
    folder = tmp_path / "pkg"
    shutil.copytree(flight_package, folder)
    src = folder / "src" / "stare.c"
    src.write_text(src.read_text() + "\n/* edited */\n")
    monkeypatch.setattr(x86, "build", lambda *a, **k: pytest.fail("an edited package was compiled"))
    with pytest.raises(ToolError, match=r"fails its check, not loaded: edited file: src/stare.c"):
        load_package(folder)


def test_a_package_whose_self_test_fails_is_refused(flight_package, tmp_path):
    """A resealed package (hashes and seal recomputed, as anyone can) with one network weight changed:
    its check passes, its self-test does not, and it is refused before any step."""
    folder = tmp_path / "pkg"
    shutil.copytree(flight_package, folder)
    nn = folder / "src" / "stare_nn.c"
    text = nn.read_text()
    i = text.index("0x1.")                   # the first hex-float constant (a weight)
    nn.write_text(text[:i + 4] + ("0" if text[i + 4] != "0" else "1") + text[i + 5:])
    _resealed(folder, edit_file=("src/stare_nn.c", nn.read_bytes()))
    with pytest.raises(ToolError, match=r"self-test reports [1-9]\d* mismatching words; refusing to fly it"):
        load_package(folder)


def test_record_layouts_are_checked_and_unknown_units_refused(flight_package):
    pkg = load_package(flight_package)
    short = Records(CONTROLLER_RECORDS.input, CONTROLLER_RECORDS.output, np.dtype([("integral", "<f4", 3)]))
    with pytest.raises(ToolError, match=r"unit controller: the C state record is 24 bytes, this staregen's is 12"):
        pkg.entry("controller", short)
    with pytest.raises(ToolError, match=r"holds no gp unit \(it holds: controller, tanh\)"):
        pkg.entry("gp", CONTROLLER_RECORDS)


def _resealed(folder, edit_file=None, edit_manifest=None):
    """A copy edited and resealed (hashes and seal recomputed), so that it passes its check."""
    doc = json.loads((folder / "manifest.json").read_text())
    if edit_file is not None:
        rel, data = edit_file
        (folder / rel).write_bytes(data)
        doc["files"][rel] = manifest.sha256_bytes(data)
    if edit_manifest is not None:
        edit_manifest(doc)
    doc.pop("sha256")
    doc["sha256"] = manifest.seal_of(doc)
    (folder / "manifest.json").write_text(json.dumps(doc, indent=2) + "\n")
    assert manifest.check(folder)[1] == []
    return folder


def test_a_source_that_is_not_utf8_is_one_line(flight_package, tmp_path):
    folder = tmp_path / "pkg"
    shutil.copytree(flight_package, folder)
    data = (folder / "src" / "stare_tanh.c").read_bytes() + b"/* \xff\xfe */\n"
    _resealed(folder, edit_file=("src/stare_tanh.c", data))
    with pytest.raises(ToolError, match=r"src/stare_tanh.c is not UTF-8 text"):
        load_package(folder)


@pytest.mark.parametrize("units, message", [
    ({"controller": {"entry": "stare); system(\"x"}}, "is not a C identifier staregen writes"),
    ({"controller": "stare"}, "is not a C identifier staregen writes"),
    ({"lqr": {"entry": "stare_lqr"}}, "unit 'lqr' is not a unit this staregen knows"),
    ({}, "the manifest lists no units"),
])
def test_hostile_unit_names_never_reach_c(flight_package, tmp_path, monkeypatch, units, message):
    folder = tmp_path / "pkg"
    shutil.copytree(flight_package, folder)
    _resealed(folder, edit_manifest=lambda doc: doc.__setitem__("units", units))
    monkeypatch.setattr(x86, "build", lambda *a, **k: pytest.fail("a hostile manifest was compiled"))
    with pytest.raises(ToolError, match=re.escape(message)):
        load_package(folder)


def test_a_missing_folder_is_one_line(tmp_path):
    with pytest.raises(ToolError, match="no such folder"):
        load_package(tmp_path / "nothing")
