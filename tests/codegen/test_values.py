"""codegen.values: the one float32 rule and number grammar every file reader uses (issue 25)."""
from __future__ import annotations

import numpy as np
import pytest

from codegen import values
from codegen.errors import CodegenError


@pytest.mark.parametrize("value, kwargs, message", [
    (1e-50, {"low": 0.0, "low_open": True}, "x: 1e-50 rounds to 0 in float32"),
    (-1e-40, {}, "x: -1e-40 rounds to a subnormal in float32"),
    (0.9999999999999999, {"low": 0.0, "high": 1.0, "high_open": True},
     "x: must be in [0, 1), got 0.9999999999999999 (as float32: 1.0)"),
    (3.4028236e38, {}, "x: must be finite (and within float32)"),
    (10 ** 400, {}, "x: must be finite (and within float32), got an integer of about 401 digits"),
    (True, {}, "x: must be a number, got True"),
    ("2_4.6", {}, "x: must be a number, got '2_4.6'"),
    (0.0, {"low": 0.0, "low_open": True}, "x: must be > 0, got 0.0"),
])
def test_float32_in_refuses_what_rounding_would_change(value, kwargs, message):
    with pytest.raises(CodegenError) as info:
        values.float32_in(value, "x", **kwargs)
    assert str(info.value).startswith(message) and "\n" not in str(info.value)


@pytest.mark.parametrize("value, kwargs", [
    (0.0, {"low": 0.0}), (1.1754944e-38, {"low": 0.0, "low_open": True}),
    (0.99999994, {"low": 0.0, "high": 1.0, "high_open": True}), (3.4028234e38, {}), (7, {"high": 7})])
def test_float32_in_returns_the_float32_of_values_that_survive(value, kwargs):
    assert values.float32_in(value, "x", **kwargs) == np.float32(value)


def test_integer_in():
    assert values.integer_in(5, "n", 1, 9) == 5
    for bad in (True, 5.0, 10, 10 ** 400):
        with pytest.raises(CodegenError, match="n: must be"):
            values.integer_in(bad, "n", 1, 9)


@pytest.mark.parametrize("text, ok", [
    ("1", True), ("-2.5e-3", True), (".5", True), ("5.", True), ("+7", True),
    ("1_000", False), ("\u0664", False), ("\u0661\u0662", False), ("0x10", False), ("", False), ("1e", False)])
def test_decimal_text_is_ascii_digits_without_underscores(text, ok):
    assert bool(values.DECIMAL_TEXT.fullmatch(text)) == ok


@pytest.mark.parametrize("text, problem", [
    ("a = 1.0\nb_c = [1, 2]\n", None),
    ('a = "1_000"  # 2_000\n', None),
    ("s = '''x\n1_0'''\n", None),
    ("a = 1_000\n", "line 1: number '1_000'"),
    ("a = 1\nb = [2, -3_0.5]\n", "line 2: number '-3_0.5'"),
    ("a = 0o17\n", "number '0o17'"),
    ("a = 0b11\n", "number '0b11'"),
])
def test_toml_number_problem_looks_at_numbers_only(text, problem):
    got = values.toml_number_problem(text)
    assert (got is None) if problem is None else (problem in got)
