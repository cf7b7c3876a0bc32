"""`staregen dp build` and `dp accuracy` on a real (tiny) OCP dataset, then `codegen --unit dp`:
the user's path from samples to flight C; the flash limit is a one-line error with the sizes."""
from __future__ import annotations

import pytest

from codegen.units.dp import tables as dp_tables
from host.cli import main


@pytest.fixture(scope="module")
def dataset(tmp_path_factory):
    out = tmp_path_factory.mktemp("dp") / "samples"
    assert main(["samples", "--n", "48", "--workers", "1", "--shard-size", "48", "--no-progress",
                 "--out", str(out)]) == 0
    return out


def test_build_then_codegen(dataset, tmp_path, capsys):
    tables = tmp_path / "tables.json"
    assert main(["dp", "build", "--data", str(dataset), "--s-limit", "32", "--out", str(tables)]) == 0
    t = dp_tables.load(tables)
    assert t.n == 36 and t.params.s_limit == 32 and t.metadata["creator"] == "staregen dp build"
    assert main(["codegen", "--unit", "dp", "--tables", str(tables), "--out", str(tmp_path / "c")]) == 0
    assert {p.name for p in (tmp_path / "c").iterdir()} >= {"dp.h", "dp.c", "sg_math.h", "sg_math.c"}
    assert t.sha256 in (tmp_path / "c" / "dp.h").read_text()
    capsys.readouterr()
    assert main(["dp", "accuracy", "--data", str(dataset), "--r", "0.5", "--s-limit", "32", "--no-progress"]) == 0
    assert "| discrete point r = 0.5, S_limit = 32 |" in capsys.readouterr().out


def test_too_many_samples_for_flash_is_one_line_with_the_sizes(dataset, tmp_path, capsys, monkeypatch):
    monkeypatch.setattr(dp_tables, "MAX_SAMPLES", 30)
    assert main(["dp", "build", "--data", str(dataset), "--out", str(tmp_path / "t.json")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "36 samples need 3,024 bytes of flash (84 per sample)" in err
    assert not (tmp_path / "t.json").exists()
    assert main(["dp", "build", "--data", str(dataset), "--n-max", "30", "--out", str(tmp_path / "t.json")]) == 0
