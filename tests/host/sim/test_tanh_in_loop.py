"""The generated tanh-law C in the loop on the paper-000 example (0.1 s): SIL (x86 via cffi) and
PIL (ARM ELF in the emulator) converge to the float64 steady state, agree with each other and
with the golden twin bit for bit at every step, and track the float64 sampled run; the cycle
report of tanh_step; `simulate --controller tanh-c|tanh-arm`."""
import json

import numpy as np
import pytest

import host.cli as cli
from host.sim import tanh_example as ex
from host.sim import tanh_in_loop
from host.sim.scenarios import configure_unit
from tools.report import cycle_report, cycle_text, verdict

PERIOD, DURATION, DT = 0.1, 40.0, 5e-4
# Measured (docs/tanh-controller.md, "Generated C"): the C and float64 runs agree to 3.2e-7 in ‖e‖
# until 13.2 s; in the final approach (13-17 s) the sampled loop amplifies any 1e-7 perturbation
# (rounding R_c(0) to float32 alone moves the float64 run by 1.2e-3 there); after 25 s they agree
# to 1.7e-8.
AGREE_UNTIL_S = 12.0


@pytest.fixture(scope="module")
def reference():
    return ex.simulate_sampled(ex.paper_scenario(), PERIOD, DURATION, DT)


@pytest.fixture(scope="module")
def sil(reference):
    return tanh_in_loop.run_in_loop("x86", PERIOD, DURATION, DT, reference=reference)


@pytest.fixture(scope="module")
def pil(reference):
    return tanh_in_loop.run_in_loop("arm", PERIOD, DURATION, DT, reference=reference)


@pytest.mark.parametrize("run", ["sil", "pil"])
def test_c_in_the_loop_converges_to_the_float64_steady_state(request, reference, run):
    m = request.getfixturevalue(run)
    assert m["golden_mismatch_steps"] == 0 and m["control_steps"] == 401
    assert m["t_settle"] is not None and m["t_settle"] <= 25.0
    assert m["e_final"] <= 2e-5 and m["we_final"] <= 1e-5 and m["u_max"] <= 4.5
    assert m["singular_samples"] == 0 and m["invalid_samples"] == 0 and m["finite"]
    assert m["e_final"] == pytest.approx(m["e_final_float64"], rel=1e-2)
    assert m["e_diff_after_25s"] <= 1e-6
    # the float64 run against itself from a float32-rounded w_c(0): the scale of the final-approach excursion
    assert m["e_diff_float64_self_max"] > 1e-5
    t = m["history"]["t"]
    diff = np.abs(np.linalg.norm(m["history"]["e"], axis=1) - np.linalg.norm(reference["e"], axis=1))
    assert diff[t <= AGREE_UNTIL_S].max() <= 1e-6


def test_float64_run_itself_moves_by_more_than_1e6_from_a_float32_initial_rate(reference):
    """Why the C is held to 1e-6 only outside the final approach: the float64 sampled run, started
    from w_c(0) rounded to float32 (a 1.5e-9 rad/s change, what any float32 interface does to it),
    leaves ||e|| within 1e-7 until 12 s and within 1e-12 after 25 s, but moves it by about 2e-5 in
    13-25 s (measured 2.1e-5): the loop amplifies 1e-9 by 1e4 there (docs/tanh-controller.md)."""
    w32 = float(np.float32(ex.WC0_EQ29[0]))
    assert w32 != ex.WC0_EQ29[0] and all(w == ex.WC0_EQ29[0] for w in ex.WC0_EQ29)
    moved = ex.simulate_sampled(ex.paper_scenario(w_c0=(w32, w32, w32)), PERIOD, DURATION, DT)
    t = reference["t"]
    diff = np.abs(np.linalg.norm(moved["e"], axis=1) - np.linalg.norm(reference["e"], axis=1))
    assert diff[t <= AGREE_UNTIL_S].max() <= 1e-7 and diff[t >= 25.0].max() <= 1e-12
    assert diff[(t >= 13.0) & (t <= 25.0)].max() > 1e-5


def test_sil_and_pil_fly_the_same_trajectory(sil, pil):
    for key in ("e", "w_e", "u", "varpi", "x2", "status"):
        np.testing.assert_array_equal(sil["history"][key], pil["history"][key])


def test_pil_reports_cycles_per_step(pil):
    cycles = pil["history"]["cycles"]
    assert cycles.shape == (401,) and pil["cycles_min"] > 1000
    # the example's own steps, strict table: measured up to 1,177 ideal (1,189 before the third round,
    # 1,443 before the second round of cycle work of docs/tanh-controller.md, "Cycles"); SPEC 8's
    # budget is 1,200, the guard is the measured value so that a regression shows
    assert pil["cycles_max"] <= 1_177


def test_cycle_report_of_tanh_step():
    """SPEC 8 budget on the gate's classes (250 vectors each, the CLI's default) plus the example."""
    unit = configure_unit("tanh", params=ex.paper_parameters())
    rep = cycle_report(unit, ("ideal",), per_class=250, seed=0)
    assert set(rep["by_class"]) == {"random", "small", "delta", "singular", "off_so3", "extreme", "special",
                                    "example"}
    # SPEC 8 (strict, ideal, <= 1,200 on the larger of bound and sampled max). Measured: sampled 1,177,
    # static bound 1,177 (strict; 1,159 / 1,159 lenient); 1,197 / 1,200 before the third round of cycle
    # work (docs/tanh-controller.md, "Cycles"). The guards are the measured values, 23 cycles of margin
    # against the budget: a change that gives some of it back fails here first
    assert rep["cycles_lenient"]["ideal"]["max"] <= 1_159 and unit.budgets.cycles == 1_200
    assert rep["cycles"]["ideal"]["max"] <= rep["bound"]["strict"]["ideal"] <= 1_177
    assert rep["bound"]["lenient"]["ideal"] <= 1_159
    assert rep["stack_bytes"] is not None and rep["stack_painted"] <= rep["stack_bytes"] <= 512
    # 26,528 B measured, of which the signed tanh rows (8,192 B), the two power tables (3,080 and
    # 4,104 B) and the log's (1,544 B); the constant tables run from CCM (copied at start-up), so
    # they count in RAM too, those four at least
    tables = 8_192 + 3_080 + 4_104 + 1_544
    assert 0 < rep["flash_bytes"] <= 27 * 1024 and tables <= rep["ram_bytes"] <= 20 * 1024 and not rep["newlib"]
    # every tanh, power and log of the law and of the 180 deg fallback is inline in tanh_step, and
    # none has a slow path the law could reach: the step calls nothing (the static bound sees no
    # sg_logf, sg_expf or sg_powf_pos either)
    assert set(rep["functions"]) == {"tanh_step"}
    text = "\n".join(cycle_text(rep))
    # the verdict is on the larger of the static bound and the sampled maximum (SPEC 8)
    worst = max(rep["bound"]["strict"]["ideal"], rep["cycles"]["ideal"]["max"])
    assert f"ideal: {verdict(worst, 1_200, 'cycles')}" in text


def test_simulate_cli_runs_the_c_in_the_loop(tmp_path, capsys):
    out = tmp_path / "sim"
    assert cli.main(["simulate", "--controller", "tanh-c", "--duration", "2", "--out", str(out)]) == 0
    metrics = json.loads((out / "metrics.json").read_text())
    assert metrics["target"] == "x86" and metrics["period"] == 0.1 and metrics["golden_mismatch_steps"] == 0
    for key in ("t_settle", "e_final", "we_final", "u_max", "e_diff_max", "e_diff_float64_self_max"):
        assert key in metrics
    for fig in ("fig8_torque.png", "fig_c_vs_float64.png"):
        assert (out / fig).read_bytes()[:4] == b"\x89PNG"
    assert "golden_mismatch_steps" in capsys.readouterr().out
