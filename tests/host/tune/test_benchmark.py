"""The side-by-side benchmark runs both simulators and reports consistent rates (no timing asserted)."""
from __future__ import annotations

import pytest

from host.tune.benchmark import measure


def test_measure_reports_both_rates():
    r = measure(scalar_runs=1, gains=2, targets=2, duration=11.0)
    assert r["batched_scenarios"] == 4 and r["scalar_runs"] == 1
    assert r["scalar_runs_per_cpu_s"] > 0 and r["batched_runs_per_cpu_s"] > 0
    assert r["ratio"] == pytest.approx(r["batched_runs_per_cpu_s"] / r["scalar_runs_per_cpu_s"], rel=0.05)
