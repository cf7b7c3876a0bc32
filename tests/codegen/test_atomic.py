"""Atomic writes: all or nothing, ordinary permissions."""
import os
import stat

import pytest

from codegen import atomic


def test_write_replaces_whole_file_with_ordinary_permissions(tmp_path):
    p = tmp_path / "a.json"
    atomic.write_json(p, {"x": 1})
    assert p.read_text() == '{\n  "x": 1\n}\n'
    mask = os.umask(0)
    os.umask(mask)
    assert stat.S_IMODE(p.stat().st_mode) == 0o666 & ~mask


def test_failed_writer_leaves_old_file_and_no_temporaries(tmp_path):
    p = tmp_path / "b.txt"
    atomic.write_text(p, "old")
    with pytest.raises(RuntimeError):
        with atomic.writing(p) as tmp:
            tmp.write_text("half")
            raise RuntimeError("killed")
    assert p.read_text() == "old"
    assert sorted(x.name for x in tmp_path.iterdir()) == ["b.txt"]


def test_directory_is_replaced_only_on_success(tmp_path):
    d = tmp_path / "out"
    with atomic.directory(d) as tmp:
        (tmp / "f").write_text("1")
    assert (d / "f").read_text() == "1"
    with pytest.raises(ValueError):
        with atomic.directory(d) as tmp:
            (tmp / "g").write_text("2")
            raise ValueError("bad input")
    assert sorted(x.name for x in d.iterdir()) == ["f"]
    assert sorted(x.name for x in tmp_path.iterdir()) == ["out"]
