"""Issue 25: the tanh law's parameter files. Every range holds for the float32 the C bakes in
(codegen.values), derived constants included; one number grammar (numbers only: no strings
through float(), no booleans, no TOML '_'); no duplicate JSON keys; capped reads of regular files."""
from __future__ import annotations

import json
import os
import threading

import pytest

from codegen.errors import CodegenError
from codegen.units.tanh import emit as tanh_emit
from codegen.units.tanh.params import TanhParamsError, example_params, load_params, params_from_mapping


def _mapping(**changes) -> dict:
    data = example_params().to_mapping()
    data.update(changes)
    return data


@pytest.mark.parametrize("key, value, message", [
    ("eps1", 1e-50, "'eps1': 1e-50 rounds to 0 in float32"),
    ("eta", 1e-300, "'eta': 1e-300 rounds to 0 in float32"),
    ("gamma", 1e-300, "'gamma': 1e-300 rounds to 0 in float32"),
    ("n1", 1e-40, "'n1': 1e-40 rounds to a subnormal"),
    ("gamma", 0.99999999, "'gamma': must be in (0, 1), got 0.99999999 (as float32: 1.0)"),
    pytest.param("k1", 10 ** 400, "'k1': must be finite (and within float32)", id="k1-400-digits"),
    ("d_max", 3.5e38, "'d_max': must be finite (and within float32)"),
])
def test_ranges_hold_after_rounding_to_float32(key, value, message):
    with pytest.raises(TanhParamsError) as info:
        params_from_mapping(_mapping(**{key: value}))
    assert message in str(info.value) and "\n" not in str(info.value)


def test_a_derived_constant_that_would_become_subnormal_is_refused():
    """d_max is a normal float32, but the u_a gain ||J^-1|| d_max of (20) is not."""
    p = params_from_mapping(_mapping(d_max=1.2e-38))
    with pytest.raises(CodegenError, match="tanh-law constant ua_gain: .* rounds to a subnormal"):
        tanh_emit.constants32(p, 0.1)


@pytest.mark.parametrize("inertia, where", [
    ([["2_4.6", 0.1, 0.0], [0.1, 2.0, -0.2], [0.0, -0.2, 4.0]], "'inertia'[0][0]: must be a number"),
    ([[3.0, True, 0.0], [True, 2.0, -0.2], [0.0, -0.2, 4.0]], "'inertia'[0][1]: must be a number"),
    ([[3.0, 1e-45, 0.0], [1e-45, 2.0, -0.2], [0.0, -0.2, 4.0]], "'inertia'[0][1]: 1e-45 rounds to a subnormal"),
])
def test_inertia_holds_numbers_only(inertia, where):
    with pytest.raises(TanhParamsError) as info:
        params_from_mapping(_mapping(inertia=inertia))
    assert where in str(info.value)


def _write_json(path, text: str):
    path.write_text(text)
    return path


def test_duplicate_json_keys_are_refused(tmp_path):
    text = json.dumps(_mapping())
    path = _write_json(tmp_path / "p.json", text[:-1] + ', "k1": 99.0}')
    with pytest.raises(TanhParamsError, match=r"p\.json: not valid JSON: duplicate key 'k1'"):
        load_params(path)


@pytest.mark.parametrize("literal", ["NaN", "Infinity", pytest.param("1" + "0" * 400, id="400-digits")])
def test_json_numbers_beyond_float32_are_one_line(tmp_path, literal):
    text = json.dumps(_mapping(k1=12345.0)).replace("12345.0", literal)
    with pytest.raises(TanhParamsError) as info:
        load_params(_write_json(tmp_path / "p.json", text))
    assert "\n" not in str(info.value) and str(info.value).startswith(str(tmp_path / "p.json"))


def _toml(data: dict) -> str:
    return "".join(f"{k} = {json.dumps(v)}\n" for k, v in data.items())


@pytest.mark.parametrize("old, new", [("k1 = 1.0", "k1 = 1_0.0"), ("k1 = 1.0", "k1 = 0x1"),
                                      pytest.param("k1 = 1.0", "k1 = " + "9" * 5000, id="5000-digits")])
def test_toml_numbers_follow_the_file_grammar(tmp_path, old, new):
    path = tmp_path / "p.toml"
    text = _toml(_mapping())
    assert old in text
    path.write_text(text.replace(old, new))
    with pytest.raises(TanhParamsError) as info:
        load_params(path)
    assert "\n" not in str(info.value) and str(info.value).startswith(str(path))


def test_the_example_file_round_trips(tmp_path):
    path = tmp_path / "p.toml"
    path.write_text(_toml(_mapping()))
    assert load_params(path) == example_params()


def test_a_fifo_is_refused_without_waiting_for_a_writer(tmp_path):
    """`generate --tanh /dev/stdin < /dev/zero` read until memory ran out: only regular files are read."""
    path = tmp_path / "p.toml"
    os.mkfifo(path)
    result = {}

    def read():
        try:
            load_params(path)
        except TanhParamsError as exc:
            result["error"] = str(exc)

    worker = threading.Thread(target=read, daemon=True)
    worker.start()
    worker.join(5.0)
    if worker.is_alive():
        os.close(os.open(path, os.O_WRONLY | os.O_NONBLOCK))   # release a blocked reader: EOF
        worker.join(5.0)
    assert result.get("error", "").startswith(f"{path}: cannot read (not a regular file)")


def test_a_file_without_the_suffix_is_refused_before_it_is_read():
    with pytest.raises(TanhParamsError, match="/dev/zero: parameter file must end in .toml or .json"):
        load_params("/dev/zero")
