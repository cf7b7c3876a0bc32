"""`staregen fuzz`: random-bit records through the sanitizer build agree with the golden model, and a
planted out-of-bounds write or a planted arithmetic change is reported."""
from __future__ import annotations

from pathlib import Path

import pytest

from codegen.artifact import random_artifact
from codegen.units.network.unit import NetworkUnit
from host.cli import main
from tools.errors import ToolError
from tools.fuzz import fuzz


class Planted(NetworkUnit):
    """The network unit with one edit in its C (the golden model is untouched)."""

    def __init__(self, artifact, old: str, new: str):
        super().__init__(artifact)
        self._edit = (old, new)

    def sources(self):
        files = dict(super().sources())
        old, new = self._edit
        assert old in files["network.c"]
        files["network.c"] = files["network.c"].replace(old, new, 1)
        return files


ARTIFACT = random_artifact((12, 40, 3), seed=2)
ROOT = Path(__file__).resolve().parents[2]


def test_clean_units_fuzz_clean(capsys, tmp_path):
    ARTIFACT.save(tmp_path / "net.json")
    assert main(["fuzz", "--artifact", str(tmp_path / "net.json"), "--n", "20000"]) == 0
    assert main(["fuzz", "--unit", "tanh", "--params", str(ROOT / "docs" / "tanh_paper000.toml"), "--n", "20000"]) == 0
    out = capsys.readouterr().out
    assert "20000 random-bit records, 0 mismatching words, 0 invariant problems" in out


def test_an_out_of_bounds_write_is_a_sanitizer_report():
    unit = Planted(ARTIFACT, "    y[2] = ", "    y[2 + (s2 > 0.0f)] = ")   # index 3 on about half the rows
    with pytest.raises(ToolError, match="sanitizer report: .*(stack-buffer-overflow|AddressSanitizer)"):
        fuzz(unit, 1000, log=lambda _: None)


def test_a_changed_operation_is_a_mismatch():
    unit = Planted(ARTIFACT, "s0 = s0 + (o0 * h.a);", "s0 = s0 - (o0 * h.a);")
    result = fuzz(unit, 2000, log=lambda _: None)
    assert result.mismatches > 0 and not result.ok
