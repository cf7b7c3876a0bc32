"""`staregen coverage`: gcov counts of a unit's C under its gate vectors; a planted unreachable
branch is reported at its line, an always-taken one is not."""
from __future__ import annotations

import argparse

import pytest

from codegen.artifact import random_artifact
from codegen.units.network.unit import NetworkUnit
from host.cli import main
from host.cli.units import PAPER000_PARAMS, PAPER002_PARAMS, report_units
from tools.coverage import LIBRARY, measure, report_lines

ARTIFACT = random_artifact((6, 8, 2), seed=5)


class Planted(NetworkUnit):
    def sources(self):
        files = dict(super().sources())
        files["network.c"] = files["network.c"].replace(
            "    y[1] = ", "    if (s1 > 0x1p+120f) {   /* PLANTED: never true */\n        y[0] = 0.0f;\n    }\n"
            "    y[1] = ", 1)
        return files


# Functions of a network's C that no step runs: the integrity check (called at start-up) and the
# stage functions kept for the stage-by-stage tests (<name>_eval runs the stages without them).
NOT_IN_THE_STEP = ("tables_crc32", "normalise", "mlp", "denormalise")


def outside_the_step(text: str, name: str = "network") -> set[int]:
    """1-based lines of the functions in NOT_IN_THE_STEP (definition to closing brace)."""
    lines = text.splitlines()
    out: set[int] = set()
    for fn in NOT_IN_THE_STEP:
        start = next(i for i, ln in enumerate(lines) if ln.startswith(("uint32_t ", name.upper() + "_STAGE void "))
                     and f"{name}_{fn}(" in ln)
        end = next(i for i in range(start, len(lines)) if lines[i] == "}")
        out |= set(range(start + 1, end + 2))
    return out


def test_network_lines_all_run_and_a_planted_branch_is_untaken():
    clean = measure(NetworkUnit(ARTIFACT), n=2_000)
    net = clean.files["network.c"]
    # every line of the step runs (not the functions outside it) and every branch is taken
    text = NetworkUnit(ARTIFACT).sources()["network.c"]
    skip = outside_the_step(text)
    assert 0 < net.lines - net.lines_hit <= len(skip)
    untaken = [ln for ln, _ in net.untaken if ln not in skip]
    assert [_bare(text.splitlines()[ln - 1].strip()) for ln in untaken] == []
    planted = Planted(ARTIFACT)
    rep = measure(planted, n=2_000)
    source = planted.sources()["network.c"]
    text, skip = source.splitlines(), outside_the_step(source)
    untaken = [ln for ln, _ in rep.files["network.c"].untaken if ln not in skip]
    assert untaken and all("PLANTED" in text[ln - 1] for ln in untaken)
    lines = report_lines(rep, planted.sources())
    assert any("PLANTED" in ln and "network.c:" in ln for ln in lines)
    assert rep.vectors == 2_000


def test_cli_writes_the_report(tmp_path, capsys):
    assert main(["coverage", "--unit", "tanh", "--vectors", "1000", "--md", str(tmp_path / "c.md")]) == 0
    text = (tmp_path / "c.md").read_text()
    assert "### Unit `tanh`" in text and "| `tanh.c` |" in text


# docs/coverage.md's triage, by source text (parentheses and spaces ignored): the only branches of
# a unit's own files that its gate vectors leave untaken. The math library's branches are all
# taken by its own run (tests/tools/test_coverage_library.py).
UNREACHABLE = {
    "controller": ("b = b << 1 > 0xFF000000u ? 0u :", "if controller_nn_tables_crc32() !=",
                   "A_bd[1] = bx1 != 0u ?", "A_bd[2] = bx2 != 0u ?",
                   "if update_modestate, status == 0u ? 1u : 0u == 0u && may_fly != 0u {",
                   "status |= CONTROLLER_STATUS_PID | status == 0u ? CONTROLLER_STATUS_DWELL : 0u;",
                   "} else if ib < CONTROLLER_NN_TANH_HALF {", "y[0] = s0 != s0 ? nan.f : s0;",
                   "y[1] = s1 != s1 ? nan.f : s1;", "y[2] = s2 != s2 ? nan.f : s2;"),
    "gp": ("k1 = k1 <= GP_K1_BAR ? k1 : GP_K1_BAR;", "k2 = k2 <= GP_K2_BAR ? k2 : GP_K2_BAR;"),
    "network": (),
    "rbf": ("return acc <= RBF_RESULT_MAX ? 1u : 0u;",),
    "tanh": (),
}
NETWORK_FILE = {"controller": ("controller_nn.c", "controller_nn"), "network": ("network.c", "network")}


def _bare(code: str) -> str:
    return code.replace("(", "").replace(")", "").replace(" ", "")


@pytest.mark.parametrize("kind", sorted(UNREACHABLE))
def test_untaken_unit_branches_are_the_documented_ones(kind):
    unit = next(u for u in report_units(argparse.Namespace(unit=kind, artifact=None, params=str(PAPER000_PARAMS),
                                                           rbf_params=str(PAPER002_PARAMS))))
    rep = measure(unit, n=10_000, n_seq=2, steps=200)
    allowed = [_bare(a) for a in UNREACHABLE[kind]]
    stray = []
    for name, cov in rep.files.items():
        if name in LIBRARY:
            continue
        source = unit.sources()[name]
        text = source.splitlines()
        skip = outside_the_step(source, NETWORK_FILE[kind][1]) if NETWORK_FILE.get(kind, ("",))[0] == name else set()
        stray += [f"{name}:{ln}: {text[ln - 1].strip()}" for ln, _ in cov.untaken
                  if ln not in skip and not any(_bare(text[ln - 1]).startswith(a) for a in allowed)]
    assert stray == []
