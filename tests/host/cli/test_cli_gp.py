"""`staregen gp table1`: the Table 1 harness from the command line (tiny synthetic sizes here; the paper-
scale run is a benchmark, BENCHMARKS.md)."""
from __future__ import annotations

import json

from tests.host.cli.package_inputs import cli


def test_table1_writes_rows_with_growth_ratios_beside_the_papers(tmp_path, capsys):
    out = tmp_path / "t1"
    code, stdout, err = cli(capsys, "gp", "table1", "--data", "synthetic", "--sizes", "40,80", "--m", "5",
                            "--exact-iterations", "3", "--sparse-iterations", "5", "--out", str(out))
    assert code == 0, err
    doc = json.loads((out / "table1.json").read_text())
    assert [r["n"] for r in doc["rows"]] == [40, 80] and doc["m"] == 5
    first, second = doc["rows"]
    assert first["exact_growth"] == 1.0 and second["exact_growth"] == second["exact_time_s"] / first["exact_time_s"]
    assert all(r["exact_mse"] > 0 and r["sparse_mse"] > 0 for r in doc["rows"])
    assert doc["paper"]["exact_s"] == [6.31, 303.78] and doc["paper"]["sparse_s"] == [1.56, 3.64]
    assert "paper: exact 6.31 -> 303.78 s (48x)" in stdout
