"""The x86-64 (cffi) build: cached by content, safe under concurrent builds, one-line errors."""
import os
import subprocess
import sys
import textwrap

import pytest

from firmware import x86
from firmware.errors import FirmwareError

SMALL_SOURCES = {"tiny.h": "float tiny_twice(float x);\n",
                 "tiny.c": '#include "tiny.h"\nfloat tiny_twice(float x) { return x + x; }\n'}
SMALL_CDEF = "float tiny_twice(float x);"
SMALL_HARNESS = '#include "tiny.h"'


def test_x86_build_is_cached_by_content(monkeypatch, tmp_path):
    monkeypatch.setenv("STAREGEN_CACHE", str(tmp_path))
    first = x86.build(SMALL_SOURCES, SMALL_CDEF, SMALL_HARNESS)
    assert first.lib.tiny_twice(1.5) == 3.0
    assert first.folder.parent == tmp_path / "x86" and first.folder.name == first.key
    changed = dict(SMALL_SOURCES, **{"tiny.c": SMALL_SOURCES["tiny.c"] + "\n"})
    assert x86.build_key(changed, SMALL_CDEF, SMALL_HARNESS) != first.key
    assert [p.name for p in (tmp_path / "x86").iterdir()] == [first.key]  # no temporaries left


def test_x86_concurrent_builds_of_one_key_are_safe(tmp_path):
    script = textwrap.dedent(f"""
        from firmware import x86
        b = x86.build({SMALL_SOURCES!r}, {SMALL_CDEF!r}, {SMALL_HARNESS!r})
        assert b.lib.tiny_twice(2.0) == 4.0
        print(b.key)
    """)
    env = dict(os.environ, STAREGEN_CACHE=str(tmp_path / "cache"), PYTHONPATH=os.getcwd())
    procs = [subprocess.Popen([sys.executable, "-c", script], env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                              text=True) for _ in range(2)]
    results = [p.communicate(timeout=120) + (p.returncode,) for p in procs]
    assert all(code == 0 for _, _, code in results), [err for _, err, _ in results]
    keys = {out.strip() for out, _, _ in results}
    assert len(keys) == 1 and [p.name for p in (tmp_path / "cache" / "x86").iterdir()] == [keys.pop()]


def test_x86_compile_error_and_missing_compiler_are_one_line_firmware_errors(monkeypatch, tmp_path):
    monkeypatch.setenv("STAREGEN_CACHE", str(tmp_path))
    broken = {"tiny.h": SMALL_SOURCES["tiny.h"], "tiny.c": "float tiny_twice(float x) { return x + 1.0; }\n"}
    with pytest.raises(FirmwareError) as info:
        x86.build(broken, SMALL_CDEF, SMALL_HARNESS)  # -Wdouble-promotion -Werror
    assert "tiny.c does not compile" in str(info.value) and "\n" not in str(info.value)
    with pytest.raises(FirmwareError, match="not found"):
        x86.build(SMALL_SOURCES, SMALL_CDEF, SMALL_HARNESS, cc="no-such-cc-staregen")
