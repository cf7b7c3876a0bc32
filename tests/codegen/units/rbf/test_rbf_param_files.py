"""Issue 26: the rbf law's parameter files (codegen/units/rbf/params.py). Every range holds for the
float32 the C bakes in (codegen.values), derived constants included; numbers only (no strings, no
booleans, integers where an integer is meant); unknown and missing keys refused; errors one line."""
from __future__ import annotations

import json
import os
import threading
from pathlib import Path

import pytest

from codegen.errors import CodegenError
from codegen.units.rbf import emit
from codegen.units.rbf.params import (PAPER_MAPPING, RbfParamsError, example_params, load_params, paper_params,
                                      params_from_mapping)

ROOT = Path(__file__).resolve().parents[4]


def _mapping(**changes) -> dict:
    data = example_params().to_mapping()
    data.update(changes)
    return data


def _refused(data: dict) -> str:
    with pytest.raises(RbfParamsError) as info:
        params_from_mapping(data)
    text = str(info.value)
    assert "\n" not in text
    return text


@pytest.mark.parametrize("key, value, message", [
    ("k3", 1e-50, "'k3': 1e-50 rounds to 0 in float32"),
    ("sigma", 1e-40, "'sigma': 1e-40 rounds to a subnormal"),
    ("alpha", 0.99999999, "'alpha': must be in (0, 1), got 0.99999999 (as float32: 1.0)"),
    ("alpha", 0.0, "'alpha': must be in (0, 1), got 0.0"),
    ("delta", 0.0, "'delta': must be > 0, got 0.0"),
    ("delta", 5e-7, "'delta': must be in [1e-06, 1], got 5e-07"),
    ("tilt_max", 1.5, "'tilt_max': must be in (0, 1.4], got 1.5"),
    ("rho_max", 0.5, "'rho_max': must be in (1, 1e+06], got 0.5"),
    ("gamma", 2e4, "'gamma': must be in (0, 10000], got 20000.0"),
    ("theta_max", [0.1] * 5 + [2e6], "'theta_max'[5]: must be in (0, 1e+06], got 2000000.0"),
    ("theta_max", [0.1] * 5 + [0.0], "'theta_max'[5]: must be > 0, got 0.0"),
    ("mass", 3.5e38, "'mass': must be finite (and within float32)"),
    pytest.param("force_max", 10 ** 400, "'force_max': must be finite (and within float32)", id="400-digits"),
    ("theorem", 3, "'theorem': must be in [1, 2], got 3"),
    ("nodes", 16, "'nodes': must be in [2, 15], got 16"),
    # 1e-37 passed once: e / s overflowed to inf, inf - inf = NaN in the basis distance, and the C's NaN
    # (positive on ARM, negative on x86) left golden == x86 but not ARM
    ("input_scale", [1e-37] + [1.0] * 11, "'input_scale'[0]: must be >= 1e-06, got 1e-37"),
])
def test_ranges_hold_after_rounding_to_float32(key, value, message):
    assert message in _refused(_mapping(**{key: value}))


@pytest.mark.parametrize("key, value, message", [
    ("nodes", 7.0, "'nodes': must be an integer, got 7.0"),
    ("nodes", True, "'nodes': must be an integer, got True"),
    ("theorem", "2", "'theorem': must be an integer"),
    ("mass", "100", "'mass': must be a number, got '100'"),
    ("k3", False, "'k3': must be a number, got False"),
    ("k1", [0.3, True, 0.1, 1.0, 1.0, 4.0], "'k1'[1]: must be a number, got True"),
    ("k2", "6.5", "'k2': must be a list of 6 numbers"),
    ("input_scale", [1.0] * 11, "'input_scale': must be a list of 12 numbers"),
    ("inertia", [11.0, 13.2, -1.0], "'inertia'[2]: must be > 0, got -1.0"),
    ("theta_max", 0.1, "'theta_max': must be a list of 6 numbers"),
    ("theta_max", [0.1, 0.01], "'theta_max': must be a list of 6 numbers"),
])
def test_numbers_only_and_vectors_of_their_length(key, value, message):
    assert message in _refused(_mapping(**{key: value}))


def test_unknown_and_missing_keys_are_refused():
    assert _refused(_mapping(bogus=1.0)) == "unknown key 'bogus'"
    data = _mapping()
    del data["k2"]
    assert _refused(data) == "missing key 'k2'"
    old = _mapping(theta_max_orbit=1.0, theta_max_attitude=0.1)     # the two bounds before one per channel
    del old["theta_max"]
    assert _refused(old) == "unknown key 'theta_max_attitude'"
    assert "must be a table/object" in _refused([1, 2])


def test_the_leakage_factor_stays_positive():
    assert "'gamma'*'lambda'" in _refused(_mapping(gamma=200.0, **{"lambda": 0.01}))
    p = params_from_mapping(_mapping(gamma=90.0, **{"lambda": 0.01}))    # 0.9 < 1: valid for periods <= 1 s
    emit.constants32(p, 1.0)
    with pytest.raises(CodegenError, match="period \\* 'gamma' \\* 'lambda' = 9 must be < 1"):
        emit.constants32(p, 10.0)


def test_derived_constants_follow_the_float32_rule():
    """Each input_scale is a normal float32, but 1 / 1e38 is a subnormal."""
    p = params_from_mapping(_mapping(input_scale=[1e38] + [1.0] * 11))
    with pytest.raises(CodegenError, match="rbf-law constant inv_scale\\[0\\]: .* rounds to a subnormal"):
        emit.constants32(p, 0.1)
    with pytest.raises(CodegenError, match="control period"):
        emit.constants32(example_params(), 0.0)


def _write(path: Path, text: str) -> Path:
    path.write_text(text)
    return path


def _toml(data: dict) -> str:
    return "".join(f"{k} = {json.dumps(v)}\n" for k, v in data.items())


def test_duplicate_json_keys_are_refused(tmp_path):
    text = json.dumps(_mapping())
    path = _write(tmp_path / "p.json", text[:-1] + ', "k3": 1.0}')
    with pytest.raises(RbfParamsError, match=r"p\.json: not valid JSON: duplicate key 'k3'"):
        load_params(path)


@pytest.mark.parametrize("old, new", [("mass = 80.0", "mass = 8_0.0"), ("mass = 80.0", "mass = 0x50"),
                                      ("mass = 80.0", "mass = nan"),
                                      pytest.param("mass = 80.0", "mass = " + "9" * 5000, id="5000-digits")])
def test_toml_numbers_follow_the_file_grammar(tmp_path, old, new):
    text = _toml(_mapping())
    assert old in text
    path = _write(tmp_path / "p.toml", text.replace(old, new))
    with pytest.raises(RbfParamsError) as info:
        load_params(path)
    assert "\n" not in str(info.value) and str(info.value).startswith(str(path))


def test_files_round_trip_and_the_paper_file_is_the_paper_mapping(tmp_path):
    assert load_params(_write(tmp_path / "p.toml", _toml(_mapping()))) == example_params()
    assert load_params(_write(tmp_path / "p.json", json.dumps(_mapping()))) == example_params()
    assert load_params(ROOT / "docs/rbf_paper002.toml") == paper_params() == params_from_mapping(PAPER_MAPPING)


def test_a_fifo_is_refused_without_waiting_for_a_writer(tmp_path):
    path = tmp_path / "p.toml"
    os.mkfifo(path)
    result = {}

    def read():
        try:
            load_params(path)
        except RbfParamsError as exc:
            result["error"] = str(exc)

    worker = threading.Thread(target=read, daemon=True)
    worker.start()
    worker.join(5.0)
    if worker.is_alive():
        os.close(os.open(path, os.O_WRONLY | os.O_NONBLOCK))
        worker.join(5.0)
    assert result.get("error", "").startswith(f"{path}: cannot read (not a regular file)")


def test_a_file_without_the_suffix_is_refused_before_it_is_read():
    with pytest.raises(RbfParamsError, match="/dev/zero: parameter file must end in .toml or .json"):
        load_params("/dev/zero")
