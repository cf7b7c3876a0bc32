"""`staregen misra`: cppcheck's MISRA addon finds a planted violation, deviations are read from the
documented TOML blocks and cover exactly their rule and files; every unit's generated C has no
undocumented finding, and every documented deviation still covers a finding."""
from __future__ import annotations

import argparse
import fnmatch
from pathlib import Path

import pytest

from codegen import units
from codegen.artifact import random_artifact
from codegen.units.network.unit import NetworkUnit
from host.cli.misra import DEVIATIONS
from host.cli.units import PAPER002_PARAMS, report_units
from tools.errors import ToolError
from tools.misra import Deviation, Finding, check, load_deviations, undocumented

TANH_PARAMS = Path(__file__).resolve().parents[2] / "docs" / "tanh_paper000.toml"

ARTIFACT = random_artifact((4, 4, 2), seed=6)


class WithGoto(NetworkUnit):
    def sources(self):
        files = dict(super().sources())
        files["network.c"] += "\nint network_planted(int x);\nint network_planted(int x)\n{\n    if (x) {\n" \
                              "        goto done;\n    }\n    x = 2;\ndone:\n    return x;\n}\n"
        return files


def test_a_planted_goto_is_found():
    clean = {f.rule for f in check(NetworkUnit(ARTIFACT))}
    planted = check(WithGoto(ARTIFACT))
    assert "misra-c2012-15.1" not in clean
    assert any(f.rule == "misra-c2012-15.1" and f.file == "network.c" for f in planted)


def test_deviations_cover_their_rule_and_files_only(tmp_path):
    doc = tmp_path / "misra.md"
    doc.write_text('text\n```toml\n[[deviation]]\nrule = "r1"\nfiles = "sg_*"\nreason = "why"\n```\n')
    devs = load_deviations(doc)
    assert devs == [Deviation("r1", "sg_*", "why")]
    findings = [Finding("sg_math.c", 1, "r1", ""), Finding("network.c", 2, "r1", ""), Finding("sg_math.c", 3, "r2", "")]
    assert undocumented(findings, devs) == findings[1:]
    doc.write_text('```toml\n[[deviation]]\nrule = "r1"\n```\n')
    with pytest.raises(ToolError, match="rule, files and reason"):
        load_deviations(doc)


def test_the_shipped_deviations_parse():
    devs = load_deviations(DEVIATIONS)
    assert devs and all(d.reason for d in devs)


def _report_findings(kind: str) -> list[Finding]:
    """cppcheck's findings for a unit bound to the inputs of `staregen misra` (report_units)."""
    args = argparse.Namespace(unit=kind, artifact=None, params=str(TANH_PARAMS), rbf_params=str(PAPER002_PARAMS))
    (unit,) = report_units(args)
    return check(unit)


@pytest.fixture(scope="module")
def report_findings():
    cache: dict[str, list[Finding]] = {}

    def get(kind: str) -> list[Finding]:
        if kind not in cache:
            cache[kind] = _report_findings(kind)
        return cache[kind]
    return get


def _show(findings: list[Finding]) -> str:
    return "\n".join(f"{f.file}:{f.line}: {f.rule}: {f.message}" for f in findings)


@pytest.mark.parametrize("kind", sorted(units.kinds()))
def test_every_unit_has_no_undocumented_finding(kind, report_findings):
    open_ = undocumented(report_findings(kind), load_deviations(DEVIATIONS))
    assert open_ == [], f"unit {kind}: {len(open_)} undocumented MISRA findings:\n{_show(open_)}"


def test_every_deviation_covers_a_current_finding(report_findings):
    findings = [f for kind in sorted(units.kinds()) for f in report_findings(kind)]
    stale = [d for d in load_deviations(DEVIATIONS)
             if not any(f.rule == d.rule and fnmatch.fnmatch(f.file, d.files) for f in findings)]
    assert stale == [], "deviations in docs/misra.md that match no current finding:\n" + "\n".join(
        f"{d.rule} ({d.files})" for d in stale)
