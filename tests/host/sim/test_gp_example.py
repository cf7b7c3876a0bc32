"""host.sim.gp_example: paper 004's takeover under the baseline and the GP law (short runs), the seam for
a unit in the loop (record_controller), the outside start and the window metrics."""
from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from codegen.units.gp.params import load_params
from codegen.units.gp.records import INPUT_DTYPE, OUTPUT_DTYPE
from host.control.takeover_laws import gp_law
from host.core.constants import DEG
from host.errors import HostError
from host.plant.takeover import TakeoverPlant
from host.sim import gp_example

DOCS = Path(__file__).resolve().parents[3] / "docs"


@pytest.fixture(scope="module")
def params():
    return load_params(DOCS / "gp_paper004.toml")


def test_the_outside_start_is_60_degrees_about_the_capture_axis():
    plant = TakeoverPlant()
    cap, out = gp_example.start_state(plant, "capture"), gp_example.start_state(plant, "outside")
    assert 2.0 * math.acos(out[3]) == pytest.approx(60.0 * DEG, rel=1e-12)
    assert 2.0 * math.acos(cap[3]) == pytest.approx(20.0 * DEG, rel=1e-12)
    np.testing.assert_allclose(out[:3] / np.linalg.norm(out[:3]), cap[:3] / np.linalg.norm(cap[:3]), rtol=1e-12)
    assert out[4:7].tolist() == cap[4:7].tolist() and not out[7:].any()
    with pytest.raises(HostError, match="unknown start"):
        gp_example.start_state(plant, "far")


def test_unknown_controller_is_one_line():
    with pytest.raises(HostError, match="unknown controller 'gp-x'"):
        gp_example.run("gp-x", None, 1.0)


def test_a_unit_step_on_records_flies_like_the_float64_law(params):
    """record_controller: a step on the unit's records (one float32 input record) in the loop."""
    law = gp_law(params)
    seen = []

    def step(record):
        seen.append(record.dtype)
        r = record[0]
        out = law(r["q"].astype(float), r["omega"].astype(float), r["h_w"].astype(float))
        rec = np.zeros(1, dtype=OUTPUT_DTYPE)
        rec["torque"], rec["mu"], rec["var"], rec["gains"] = out.torque, out.mu, out.var, out.gains
        return rec

    unit = gp_example.fly(gp_example.record_controller(step), params, 5.0, "capture")
    ref = gp_example.fly(gp_example.controller_for("gp", params), params, 5.0, "capture")
    assert seen[0] == INPUT_DTYPE and len(seen) == 50
    np.testing.assert_allclose(unit["angle"], ref["angle"], atol=1e-6 * DEG)
    np.testing.assert_allclose(unit["gains"][:-1], ref["gains"][:-1], rtol=1e-5)


@pytest.mark.parametrize("controller, mode", [("gp-c", "SIL x86"), ("gp-arm", "PIL ARM emulator")])
def test_the_generated_c_in_the_loop_flies_like_the_float64_law(params, controller, mode):
    """SIL / PIL: no step differs from the golden twin, and the float32 C stays within float32 rounding of
    the float64 law (attitude to 1e-4 deg, torque to 1e-4 N*m over 3 s from the capture state)."""
    m = gp_example.run(controller, params, 3.0)["metrics"]
    assert m["mode"] == mode and m["golden_mismatch_steps"] == 0
    assert m["max_angle_diff_deg"] < 1e-4 and m["max_torque_diff"] < 1e-4 and m["max_mu_diff"] < 1e-4
    assert m["max_angle_diff_deg"] > 0 or m["max_torque_diff"] > 0     # float32 against float64: not the same run
    if controller == "gp-arm":
        assert 0 < m["cycles_min"] <= m["cycles_max"] <= 15_000
    else:
        assert "cycles_max" not in m


def test_window_metrics_against_hand_values():
    t = np.arange(0.0, 200.1, 0.1)
    gains = np.column_stack([np.where(t < 100.0, 10.0, 4.0), np.where(t < 100.0, 100.0, 72.0)])
    frac = np.where(t < 100.0, 0.5, 0.0)
    frac[-1] = np.nan                                            # the last row has no command
    hist = {"t": t, "gains": gains, "var_fraction": frac, "mu": np.zeros((len(t), 3)),
            "d0": np.full((len(t), 3), 0.02)}
    m = gp_example.gp_metrics(hist, "gp")
    assert m["gains_first_60s"] == [10.0, 100.0] and m["gains_last_60s"] == [4.0, 72.0]
    assert m["var_fraction_first_60s"] == 0.5 and m["var_fraction_last_60s"] == 0.0
    np.testing.assert_allclose(m["mu_rms_error"], [0.02] * 3)


def test_outside_start_raises_the_variance_and_the_gains(params):
    cap = gp_example.run("gp", params, 20.0, "capture")["metrics"]
    out = gp_example.run("gp", params, 20.0, "outside")["metrics"]
    assert out["var_fraction_first_60s"] > 2.0 * cap["var_fraction_first_60s"]
    assert out["gains_first_60s"][0] > cap["gains_first_60s"][0] and out["gains_first_60s"][1] > cap["gains_first_60s"][1]
    for m in (cap, out):
        assert 4.0 <= m["gains_first_60s"][0] <= 16.0 and 72.0 <= m["gains_first_60s"][1] <= 144.0
        assert m["finite"] and m["max_abs_torque"] <= 1.0


def test_the_gp_mean_tracks_the_true_unknown_term(params):
    m = gp_example.run("gp", params, 30.0, "capture")["metrics"]
    assert all(e < 0.5 * r for e, r in zip(m["mu_rms_error"], m["d0_rms"])), (m["mu_rms_error"], m["d0_rms"])


def test_baseline_and_gp_write_their_figures(params, tmp_path):
    gp_example.run("gp-baseline", params, 3.0, "capture", out_dir=tmp_path / "b")
    gp_example.run("gp", params, 3.0, "outside", out_dir=tmp_path / "g")
    assert {p.name for p in (tmp_path / "b").iterdir()} == {"metrics.json", "history.npz", "fig4_attitude.png",
                                                            "fig5_rates.png", "fig6_torque.png"}
    assert {"fig7_variance_gains.png", "fig_gp_mean.png"} <= {p.name for p in (tmp_path / "g").iterdir()}
