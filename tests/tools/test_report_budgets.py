"""SPEC 8 has no whole-step `art` budget (issue 25): a step that runs its code once per call has
an `art` figure set by its footprint (SPEC 7: ideal + 5 cycles per flash line it touches), so the
report gives the figure and the line misses and judges nothing; the network path, a loop, keeps
its `art` budget."""
from __future__ import annotations

from codegen.units.controller.unit import BUDGETS as CONTROLLER
from codegen.units.network.unit import BUDGETS as NETWORK
from codegen.units.tanh.unit import BUDGETS as TANH
from tools.report import art_verdict


def test_no_whole_step_art_budget_is_stated():
    assert CONTROLLER.cycles_art is None and TANH.cycles_art is None
    assert CONTROLLER.cycles == 5_000 and NETWORK.cycles_art == 3_300


def test_a_step_without_art_budget_reports_its_figure_and_line_misses():
    text = art_verdict(7_244, 4_839, CONTROLLER.cycles_art)      # the figures of README / BENCHMARKS
    assert "OVER" not in text and "no budget" in text
    assert text.startswith("7244 cycles") and f"{(7_244 - 4_839) // 5} flash-line misses" in text


def test_the_network_path_is_still_judged_on_art():
    assert art_verdict(3_298, 2_983, NETWORK.cycles_art) == "within budget (3298 <= 3300 cycles)"
    assert art_verdict(3_400, 2_983, NETWORK.cycles_art).startswith("OVER budget by 100 cycles")
