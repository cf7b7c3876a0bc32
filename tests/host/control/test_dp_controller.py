"""The discrete-point law flown in the staring loop (host/control/dp_controller.py): tables sampled
from the stand-in network (the PID law's fit), so the law should fly like it; the generated C (SIL)
equals its golden model on every step and the float64 law within 1 % in J; outside the Table 2
envelope the PID flies; bad options are one-line errors."""
from __future__ import annotations

import numpy as np
import pytest

from codegen.artifact import TABLE2_MAX, TABLE2_MIN
from codegen.units.dp import tables as dp_tables
from codegen.units.dp.params import DpParams
from host.cli import main
from host.control.controllers import Measurement
from host.control.dp_controller import DpController, GeneratedLaw, load_tables, make_dp_controller
from host.control.nn_controller import load_artifact, make_nn_controller, network64
from host.sim.metrics import staring_metrics
from host.sim.simulator import SimConfig, simulate
from host.sim.targets import central_target

DURATION = 15.0


@pytest.fixture(scope="module")
def tables_file(tmp_path_factory):
    rng = np.random.default_rng(4)
    lo, hi = np.array(TABLE2_MIN), np.array(TABLE2_MAX)
    X = lo + (hi - lo) * rng.uniform(size=(800, 12))
    a = load_artifact(None)
    Y = np.array([network64(a, x) for x in X])
    path = tmp_path_factory.mktemp("dp") / "tables.json"
    dp_tables.from_arrays(X, Y, DpParams(r=0.3, s_limit=32, n_min=26)).save(path)
    return str(path)


def _fly(controller):
    tg = central_target()
    h = simulate(controller, tg.lon, tg.lat, SimConfig(duration=DURATION))
    return staring_metrics(h.t, h.A_bd, h.omega_e, t_end=DURATION), h


def test_the_law_flies_like_the_network_it_was_sampled_from(tables_file):
    dp, _ = _fly(make_dp_controller(torque_limit=1.0, control_period=0.1, tables=tables_file))
    nn, _ = _fly(make_nn_controller(torque_limit=1.0, control_period=0.1, artifact=None))
    assert dp.J == pytest.approx(nn.J, rel=0.05)


def test_sil_equals_its_golden_model_and_the_float64_law_within_one_percent(tables_file):
    generated = GeneratedLaw(load_tables(tables_file), golden_twin=True)
    sil, _ = _fly(DpController("dp-c", generated, 1.0, 0.1))
    dp, _ = _fly(make_dp_controller(torque_limit=1.0, control_period=0.1, tables=tables_file))
    assert generated.loop.mismatch_steps == 0 and len(generated.loop.outputs) > 100
    assert sil.J == pytest.approx(dp.J, rel=0.01)


def test_outside_the_envelope_the_pid_flies(tables_file):
    c = make_dp_controller(torque_limit=1.0, control_period=0.1, tables=tables_file)
    m = Measurement(t=0.0, A_bo=np.array([0.3, 0.0, 0.0]), omega_b=np.zeros(3), lon=central_target().lon,
                    lat=central_target().lat, jd_days=2460000, sec_of_day=0.0,
                    R_s=np.array([7.0e6, 0.0, 0.0]), V_s=np.array([0.0, 7.5e3, 0.0]))
    assert c.step(m).mode == "pid"


@pytest.mark.parametrize("argv, message", [
    (["--controller", "dp"], "needs --tables FILE"),
    (["--controller", "pid", "--tables", "x.json"], "--tables applies to dp, dp-c only"),
    (["--controller", "dp", "--tables", "missing.json"], "no such file"),
])
def test_bad_options_are_one_line_errors(argv, message, tmp_path, capsys):
    assert main(["simulate", "--duration", "12", *argv, "--out", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and message in err
