"""Issue 25: the discrete-point settings and tables file. Every real holds its range as the float32
the C bakes in (codegen.values: 1e-300 is not a positive tukey_c once rounded), whether it comes
from code or from a sealed tables file; numbers are numbers (no booleans, no strings); the file
is strict JSON (no duplicate keys) read from a regular file."""
from __future__ import annotations

import json

import pytest

from codegen.artifact import ArtifactError, payload_sha256
from codegen.units.dp import tables as T
from codegen.units.dp.params import DpParams, DpParamsError


@pytest.mark.parametrize("changes, message", [
    ({"tukey_c": 1e-300}, "discrete-point tukey_c: 1e-300 rounds to 0 in float32"),
    ({"tukey_c": 1e-39}, "discrete-point tukey_c: 1e-39 rounds to a subnormal"),
    ({"ridge": 1e-300}, "discrete-point ridge: 1e-300 rounds to 0 in float32"),
    ({"r": 0.99999999999}, "discrete-point r: must be in (0, 1), got 0.99999999999 (as float32: 1.0)"),
])
def test_ranges_hold_after_rounding_to_float32(changes, message):
    with pytest.raises(DpParamsError) as info:
        DpParams(**changes).validate()
    assert message in str(info.value)


def test_zero_ridge_stays_valid():
    assert DpParams(ridge=0.0).validate().ridge == 0.0


@pytest.fixture(scope="module")
def document():
    return json.loads(json.dumps(T.random_tables(60, DpParams(s_limit=32, n_min=20), seed=3).document()))


def _write_sealed(path, payload) -> None:
    path.write_text(json.dumps({"format": T.FORMAT, "version": T.VERSION, "sha256": payload_sha256(payload),
                                "payload": payload}))


@pytest.mark.parametrize("key, value, message", [
    ("tukey_c", 1e-300, "tukey_c: 1e-300 rounds to 0"),
    ("ridge", 1e-300, "ridge: 1e-300 rounds to 0"),
    ("iterations", True, "IRLS iterations must be an integer"),
    ("tukey_c", "4.685", "tukey_c must lie in"),
])
def test_a_sealed_tables_file_follows_the_same_rule(document, tmp_path, key, value, message):
    payload = json.loads(json.dumps(document["payload"]))
    payload["params"][key] = value
    _write_sealed(tmp_path / "t.json", payload)
    with pytest.raises(ArtifactError) as info:
        T.load(tmp_path / "t.json")
    assert "payload.params" in str(info.value) and message in str(info.value) and "\n" not in str(info.value)


def test_duplicate_keys_are_refused(document, tmp_path):
    text = json.dumps(document)
    (tmp_path / "t.json").write_text(text.replace('"payload": {', '"payload": {"params": 1, ', 1))
    with pytest.raises(ArtifactError, match="not valid JSON: duplicate key 'params'"):
        T.load(tmp_path / "t.json")


def test_only_regular_files_are_read(tmp_path):
    with pytest.raises(ArtifactError, match="not a regular file"):
        T.load(tmp_path)
