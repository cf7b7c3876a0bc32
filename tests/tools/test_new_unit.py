"""Adding a unit is shown, not claimed: a throw-away unit (tests/tools/throwaway_unit/, a saturated
linear law u = clip(K x)) registered from a folder of its own gets the gate, the cycle report,
SIL/PIL in the loop and the CLI without a line of code outside its folder."""
import json

import numpy as np
import pytest

from codegen import units
from host.cli import main
from tests.codegen.units import unit_checks as checks
from tests.tools import throwaway_unit
from tools.gate import run_gate
from tools.inloop import InTheLoop
from tools.report import cycle_report

pytestmark = pytest.mark.usefixtures("private_cache")  # conftest: a build cache of its own


@pytest.fixture(scope="module")
def unit():
    units.register(throwaway_unit.KIND)
    yield checks.example_unit(throwaway_unit.KIND)
    units.unregister(throwaway_unit.KIND.name)


def test_gate_for_free(unit):
    lines = []
    result = run_gate(unit, 3_000, seed=1, log=lines.append)
    assert result.ok and set(result.counts) == {"inside", "outside", "special"}, lines
    assert any("arm vs golden" in ln and "identical" in ln for ln in lines)


def test_every_unit_property_holds(unit):
    for check in (checks.check_one_ulp_change_is_caught, checks.check_golden_refuses_float64,
                  checks.check_golden_follows_spec_6, checks.check_no_libm_no_malloc,
                  checks.check_a_drifted_dtype_is_refused, checks.check_records_are_independent):
        check(unit)
    checks.check_regeneration_is_byte_identical(throwaway_unit.KIND)


def test_cycles_for_free(unit):
    rep = cycle_report(unit, ("ideal", "art"), per_class=20, seed=0)
    assert rep["entry_fn"] == "satlin_step" and set(rep["by_class"]) == {"inside", "outside", "special"}
    assert 0 < rep["cycles"]["ideal"]["max"] <= unit.budgets.cycles <= rep["cycles"]["art"]["max"] * 10
    assert 0 < rep["flash_bytes"] <= unit.budgets.flash and rep["objects"] == ["satlin.o"]
    assert rep["stack_bytes"] is not None and rep["stack_painted"] <= rep["stack_bytes"] <= unit.budgets.stack


@pytest.mark.parametrize("target", ["x86", "arm"])
def test_sil_and_pil_for_free(unit, target):
    loop = InTheLoop(unit, target)
    for x in ([0.1, -0.2, 0.3], [5.0, 0.0, -5.0], [np.nan, 1.0, 0.0]):
        rec = np.zeros(1, dtype=unit.input_dtype)
        rec["x"] = x
        out = loop.step(rec)
        assert np.all(np.abs(out["u"]) <= 1.0)
    assert loop.mismatch_steps == 0 and len(loop.outputs) == 3
    assert (len(loop.cycles) == 3 and min(loop.cycles) > 0) if target == "arm" else loop.cycles == []


def test_cli_for_free(unit, tmp_path, capsys):
    assert main(["verify", "--unit", "satlin", "--vectors", "900"]) == 0
    assert "PASS" in capsys.readouterr().out
    assert main(["cycles", "--unit", "satlin", "--per-class", "5", "--json", str(tmp_path / "c.json")]) == 0
    assert json.loads((tmp_path / "c.json").read_text())["entries"]["satlin"]["unit"] == "satlin"
    assert main(["codegen", "--unit", "satlin", "--out", str(tmp_path / "src")]) == 0
    assert sorted(p.name for p in (tmp_path / "src").iterdir()) == ["satlin.c", "satlin.h"]
