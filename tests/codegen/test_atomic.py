"""Atomic writes: all or nothing, ordinary permissions; output folders locked, and only a run's own
temporaries (or a dead run's) ever removed."""
import fcntl
import os
import stat
import subprocess
import sys
from pathlib import Path

import pytest

from codegen import atomic
from codegen.errors import CodegenError


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


# issue 25 defects 2 and 4: only this run's temporaries are ever removed; a lock on the folder

def dead_pid() -> int:
    """The pid of a process that has exited (a killed run's)."""
    proc = subprocess.Popen([sys.executable, "-c", "pass"])
    proc.wait()
    return proc.pid


def test_a_sibling_old_folder_is_never_deleted(tmp_path):
    d = tmp_path / "out"
    d.mkdir()
    (d / "f").write_text("1")
    old = tmp_path / ".out.old"
    old.mkdir()
    (old / "keep.txt").write_text("someone else's")
    for _ in range(2):
        with atomic.directory(d) as tmp:
            (tmp / "g").write_text("2")
    assert (old / "keep.txt").read_text() == "someone else's"
    assert sorted(x.name for x in tmp_path.iterdir()) == [".out.old", "out"]
    assert sorted(x.name for x in d.iterdir()) == ["g"]


def test_a_failed_swap_puts_the_old_folder_back(tmp_path, monkeypatch):
    d = tmp_path / "out"
    with atomic.directory(d) as tmp:
        (tmp / "f").write_text("1")
    real_replace = os.replace

    def failing_second_rename(src, dst):
        if str(src).endswith(".tmp") and Path(dst) == d:
            raise OSError(28, "No space left on device")
        real_replace(src, dst)

    monkeypatch.setattr(atomic.os, "replace", failing_second_rename)
    with pytest.raises(OSError):
        with atomic.directory(d) as tmp:
            (tmp / "g").write_text("2")
    assert sorted(x.name for x in d.iterdir()) == ["f"]
    assert sorted(x.name for x in tmp_path.iterdir()) == ["out"]


def test_temporaries_of_a_dead_run_are_removed_and_nothing_else(tmp_path):
    d = tmp_path / "out"
    dead, alive = dead_pid(), os.getppid()
    stale = [tmp_path / f".out.{dead}.abcd1234.tmp", tmp_path / f".out.{dead}.x_9y8z7w.old"]
    kept = [tmp_path / f".out.{alive}.abcd1234.tmp",      # a live run's (its own lock decides)
            tmp_path / ".out.abcd1234.tmp",               # no pid: not provably a dead run's
            tmp_path / ".out.old", tmp_path / f".other.{dead}.abcd1234.tmp"]
    for folder in stale + kept:
        folder.mkdir()
        (folder / "x").write_text("x")
    with atomic.directory(d) as tmp:
        (tmp / "f").write_text("1")
    assert not any(p.exists() for p in stale)
    assert all((p / "x").exists() for p in kept)
    assert (d / "f").read_text() == "1" and not (tmp_path / ".out.lock").exists()


def hold_lock(folder: Path):
    """Lock `folder` as another run would: flock on `.<name>.lock` beside it (a new open file)."""
    fd = os.open(folder.with_name(f".{folder.name}.lock"), os.O_RDWR | os.O_CREAT)
    fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
    return fd


def test_a_locked_folder_is_refused_and_left_alone(tmp_path):
    d = tmp_path / "out"
    with atomic.directory(d) as tmp:
        (tmp / "f").write_text("1")
    fd = hold_lock(d)
    try:
        with pytest.raises(CodegenError, match="in use by another run"):
            with atomic.directory(d) as tmp:
                (tmp / "g").write_text("2")
    finally:
        os.close(fd)
    assert sorted(x.name for x in d.iterdir()) == ["f"]
    assert sorted(x.name for x in tmp_path.iterdir()) == [".out.lock", "out"]   # the holder's file, kept


def test_the_current_folder_is_refused_in_one_line(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    with pytest.raises(CodegenError, match="has no name"):
        with atomic.directory(".") as tmp:
            (tmp / "f").write_text("1")
    assert list(tmp_path.iterdir()) == []


def test_a_symlinked_output_is_replaced_and_its_target_kept(tmp_path):
    target = tmp_path / "target"
    target.mkdir()
    (target / "keep.txt").write_text("kept")
    (tmp_path / "out").symlink_to(target)
    with atomic.directory(tmp_path / "out") as tmp:
        (tmp / "f").write_text("1")
    assert not (tmp_path / "out").is_symlink() and (tmp_path / "out" / "f").read_text() == "1"
    assert (target / "keep.txt").read_text() == "kept"
    assert sorted(x.name for x in tmp_path.iterdir()) == ["out", "target"]
