"""Issue 25 defect 14: one number grammar (ASCII digits, no underscores) for the numbers a user types;
Python's int() and float() accept more (`1_00`, Arabic-Indic and full-width digits)."""
from __future__ import annotations

import math

import pytest

from codegen.number_text import parse_integer, parse_real


@pytest.mark.parametrize("text, value", [("0", 0), ("17", 17), ("+7", 7), ("-3", -3), (" 4 ", 4), ("\t12\n", 12)])
def test_integers_in_ascii_digits(text, value):
    assert parse_integer(text) == value


LOOSE = ["1_00", "\u0664", " \u0664 ", "\uff11", "\u0661\u0662", "\u20034"]    # int() takes every one


def test_python_takes_what_the_grammar_refuses():
    assert [int(t) for t in LOOSE] == [100, 4, 4, 1, 12, 4]


@pytest.mark.parametrize("text", LOOSE + ["1e3", "0x10", "1.0", "", " ", "1 2", "nan"])
def test_everything_else_is_not_an_integer(text):
    with pytest.raises(ValueError):
        parse_integer(text)


@pytest.mark.parametrize("text, value", [("1.5", 1.5), (".5", 0.5), ("5.", 5.0), ("-1e-3", -1e-3), ("2E+2", 200.0),
                                         (" 30 ", 30.0), ("1.7e308", 1.7e308)])
def test_reals_in_ascii_digits(text, value):
    assert parse_real(text) == value


def test_special_reals_are_read_for_the_caller_to_refuse():
    assert math.isnan(parse_real("nan")) and parse_real("-Inf") == -math.inf and parse_real("1e400") == math.inf


@pytest.mark.parametrize("text", ["1_20", "3_0.5", "1e1_0", "\u0664.5", "\uff11.0", "1e", "e5", ".", "-", "",
                                  "infinit", "0x1p3"])
def test_everything_else_is_not_a_real(text):
    with pytest.raises(ValueError):
        parse_real(text)
