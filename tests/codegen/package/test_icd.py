"""The ICD: every field of every unit documented exactly once, status masks from the specs, the
timing figures derived from the evidence, configuration text escaped, deterministic output."""
from __future__ import annotations

import re

import pytest

from codegen import units
from codegen.package.icd import cell, render_icd
from codegen.units.controller import spec as cs
from codegen.units.tanh import golden as tanh_golden
from host.control.nn_controller import default_package_config
from tests.codegen.units.unit_checks import example_unit
from host.sim.scenarios import package_units
from codegen.artifact import random_artifact


@pytest.mark.parametrize("kind", sorted(units.kinds()))
def test_field_docs_cover_exactly_the_dtype_fields(kind):
    unit = example_unit(units.get(kind))
    docs = unit.field_docs()
    for role in ("input", "output", "state"):
        dtype = getattr(unit, f"{role}_dtype")
        if dtype is None:
            assert role not in docs
            continue
        assert [d.name for d in docs[role]] == list(dtype.names), (kind, role)
        assert all(d.unit and d.frame and d.range and d.meaning for d in docs[role])
    masks = [b.mask for b in unit.status_bits()]
    assert len(set(masks)) == len(masks) and all(m > 0 for m in masks)
    assert all(a & b == 0 for i, a in enumerate(masks) for b in masks[i + 1:])


def test_status_masks_are_the_spec_constants():
    unit = example_unit(units.get("controller"))
    got = {b.name: b.mask for b in unit.status_bits()}
    assert got["STATUS_PID"] == cs.STATUS_PID and got["STATUS_DWELL"] == cs.STATUS_DWELL
    assert got["STATUS_BOUNDS_MASK"] == sum(1 << (cs.STATUS_BOUND_SHIFT + i) for i in range(12))
    assert sum(got.values()) == (1 << 17) - 1                 # bits 0..16, each once
    tanh = {b.name: b.mask for b in example_unit(units.get("tanh")).status_bits()}
    assert tanh == {"STATUS_SINGULAR": tanh_golden.STATUS_SINGULAR, "STATUS_INVALID_INPUT": tanh_golden.STATUS_INVALID_INPUT}


def evidence_for(unit, step_max: int) -> dict:
    stats = {m: {"min": 100, "median": 200, "max": step_max + k} for k, m in enumerate(("ideal", "art", "pessimistic"))}
    return {"kind": unit.kind, "entry": unit.entry,
            "gate": {"vectors": 1000, "sequences": 2, "steps": 10, "pass": True,
                     "targets": {"golden": {"invariant_problems": 0}, "x86": {"mismatches": 0}, "arm": {"mismatches": 0}}},
            "selftest_vectors": {"n": 8, "classes": {"a": 8}, "targets": {}},
            "cycles": {"step": stats, "reference": {"ideal": 4321}, "functions": {unit.step_symbol: stats}},
            "memory": {"flash_bytes": 11, "ram_bytes": 0, "state_bytes": 20, "stack_bytes": 360}}


def render(config=None, step_max=16_800):
    cfg = default_package_config()
    pkg_units = package_units(cfg, random_artifact((12, 40, 3), seed=1))
    config = config or cfg.to_mapping()
    ev = {"units": {"controller": evidence_for(pkg_units["controller"], step_max)}, "clock_hz": 168_000_000,
          "paper_budget_cycles": 554_400, "package_build": {"x86": {"selftest_mismatches": 0}}}
    return render_icd("stare", pkg_units, config, ev, {"common": ["-std=c99", "-ffp-contract=off"],
                                                       "arm_cpu": ["-mcpu=cortex-m4"], "compiler": "gcc 1"})


def test_icd_content():
    text = render()
    unit = example_unit(units.get("controller"))
    for role in ("input", "output", "state"):
        for name in getattr(unit, f"{role}_dtype").names:
            assert f"| `{name}` |" in text, name
    # 16,800 cycles at 168 MHz are 100.00 µs; the art row (16,801) 100.01 µs
    assert re.search(r"\| ideal \| 100 \| 200 \| 16800 \| 100\.00 \| 3\.03 % \|", text)
    assert "| art | 100 | 200 | 16801 | 100.01 |" in text
    assert "| `pid.kp` | [17.0, 54.0, 18.0] |" in text and "`-std=c99 -ffp-contract=off`" in text
    assert "`STARE_STATUS_SATURATED` | `0x00004000`" in text and "ideal 4321" in text
    assert "round to nearest even" in text and "FZ = 0" in text


def test_text_from_files_cannot_break_a_table():
    cfg = default_package_config().to_mapping()
    cfg["package"] = dict(cfg["package"], name="a|b\n| injected | row |")
    text = render(cfg)
    line = next(ln for ln in text.splitlines() if ln.startswith("| `package.name`"))
    assert line.count("|") - line.count("\\|") == 3 and "injected" in line
    assert cell("x`y|z\nw") == "x'y\\|z w"


def test_deterministic():
    assert render() == render()
