"""`staregen misra`: cppcheck's MISRA addon finds a planted violation, deviations are read from the
documented TOML blocks and cover exactly their rule and files."""
from __future__ import annotations

import pytest

from codegen.artifact import random_artifact
from codegen.units.network.unit import NetworkUnit
from tools.errors import ToolError
from tools.misra import Deviation, Finding, check, load_deviations, undocumented

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
    from host.cli.misra import DEVIATIONS
    devs = load_deviations(DEVIATIONS)
    assert devs and all(d.reason for d in devs)
