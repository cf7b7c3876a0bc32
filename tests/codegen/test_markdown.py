"""Issue 25 defect 15: the one Markdown escaping function keeps any text literal and on one line."""
from __future__ import annotations

from codegen.markdown import escape


def test_escape_keeps_text_literal_on_one_line():
    assert escape("a\n## b") == "a ## b" and escape("# b") == "\\# b" and escape("## b") == "#\\# b"
    assert escape("1. x") == "1\\. x" and escape("1.5") == "1.5"
    assert escape("- x") == "\\- x" and escape("a - b") == "a - b"
    assert escape("<img src=x onerror=y>") == "&lt;img src=x onerror=y&gt;" and escape("&#60;") == "&amp;#60;"
    assert escape("[a](javascript:b)") == "\\[a\\](javascript:b)"
    assert escape("a|b`c_d*e~f\\g") == "a\\|b\\`c\\_d\\*e\\~f\\\\g"
    assert escape("a\u202eb\x00c\u2028d") == "a\ufffdb\ufffdc d"
    assert escape("PID (tuned) 0.66") == "PID (tuned) 0.66" and escape(1.5) == "1.5"
