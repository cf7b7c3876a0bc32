"""The float64 twin of Fig. 2 (host/control/nn_controller.py) and the golden model against it."""
import dataclasses

import numpy as np
import pytest

from codegen.units.controller import spec as cs
from codegen.units.controller import golden as gc
from codegen.units.controller.vectors import Geometry
from host.core.constants import DEG
from host.core.frames import L_oi
from host.gnc.guidance import desired_state
from host.core.rotations import dcm_from_euler312, euler312_from_dcm
from host.sim.scenarios import StaringScenario
from host.control.controllers import ControlOutput, Measurement, build_controller
from host.control.nn_controller import ModeLogic, NnController, TrackingPid, flight_config, load_artifact, network64
from host.gnc.preprocess import preprocess
from host.sim.simulator import SimConfig, environment_track, simulate
from host.sim.targets import central_target

TG = central_target()


@pytest.fixture(scope="module")
def artifact():
    return load_artifact(None)   # the stand-in network fitted to the PID law


def measurement(k: int = 300, dA=(0.0, 0.0, 0.0), dw=(0.0, 0.0, 0.0)) -> Measurement:
    """Sensors on the central-target pass at sample k (0.02 s steps) with errors in S_d (rad, rad/s)."""
    env = environment_track(1001, 0.02)
    g = Geometry(env.jd_days[k:k + 1], env.sec_of_day[k:k + 1], env.R[k:k + 1], env.V[k:k + 1],
                 np.array([TG.lon]), np.array([TG.lat]))
    d = desired_state(g.jd, g.sec, g.R, g.V, g.lon, g.lat)
    L_bo = dcm_from_euler312(np.array([dA])) @ d.L_di @ np.swapaxes(L_oi(g.R, g.V), -1, -2)
    return Measurement(t=k * 0.02, jd_days=int(g.jd[0]), sec_of_day=float(g.sec[0]),
                       A_bo=euler312_from_dcm(L_bo)[0], omega_b=d.omega_d[0] + np.array(dw),
                       R_s=g.R[0], V_s=g.V[0], lon=TG.lon, lat=TG.lat)


def test_inside_the_envelope_the_network_flies(artifact):
    c = NnController(artifact, flight_config())
    m = measurement(dA=np.array([0.01, -0.005, 0.002]) * DEG, dw=np.array([0.001, 0.0, -0.002]) * DEG)
    out = c.step(m)
    x = preprocess(m)
    np.testing.assert_allclose(x.A_bd / DEG, [0.01, -0.005, 0.002], atol=1e-9)
    assert out.mode == "nn" and out.info["status"] == 0
    np.testing.assert_allclose(out.torque, network64(artifact, x.network_inputs_deg()), rtol=0, atol=1e-15)
    # the stand-in approximates the Table 1 law inside the envelope
    pid = -(np.array([17, 54, 18]) * x.A_bd / DEG + np.array([46, 77, 50]) * x.omega_e / DEG)
    np.testing.assert_allclose(out.torque, pid, atol=0.05)


@pytest.mark.parametrize("axis", range(6))
def test_each_error_bound_hands_over_to_the_pid_with_its_flag(artifact, axis):
    c = NnController(artifact, flight_config())
    dA, dw = np.zeros(3), np.zeros(3)
    (dA if axis < 3 else dw)[axis % 3] = (0.0201 if axis < 3 else 0.00401) * DEG
    out = c.step(measurement(dA=dA, dw=dw))
    bit = 1 << (cs.STATUS_BOUND_SHIFT + 6 + axis)
    assert out.mode == "pid" and out.info["status"] & cs.STATUS_PID
    assert out.info["status"] & cs.STATUS_BOUNDS_MASK == bit
    x = preprocess(measurement(dA=dA, dw=dw))
    raw = -(np.array([17.0, 54, 18]) * x.A_bd / DEG + np.array([46.0, 77, 50]) * x.omega_e / DEG)
    np.testing.assert_allclose(out.torque, np.clip(raw, -1, 1), atol=1e-12)


def test_dwell_before_the_network_resumes():
    logic = ModeLogic(dwell_steps=10)
    assert logic.update(True) == cs.MODE_NN
    assert logic.update(False) == cs.MODE_PID
    modes = [logic.update(True) for _ in range(12)]
    assert modes[:9] == [cs.MODE_PID] * 9 and modes[9:] == [cs.MODE_NN] * 3
    assert logic.update(False) == cs.MODE_PID and logic.count == 0   # one bad step restarts the dwell


@pytest.mark.parametrize("field", ["A_bo", "omega_b", "R_s", "V_s"])
@pytest.mark.parametrize("value", [np.nan, np.inf, -np.inf])
def test_non_finite_inputs_fly_the_pid_with_a_finite_torque(artifact, field, value):
    c = NnController(artifact, flight_config())
    m = measurement()
    bad = np.array(getattr(m, field), float)
    bad[1] = value
    out = c.step(dataclasses.replace(m, **{field: bad}))
    assert out.mode == "pid" and out.info["status"] & cs.STATUS_INPUT_INVALID
    assert np.all(np.isfinite(out.torque)) and np.all(np.abs(out.torque) <= 1.0)


def test_integrator_tracks_while_the_network_flies():
    cfg = dataclasses.replace(flight_config(), ki=(0.5, 0.5, 0.5))
    pid = TrackingPid(cfg)
    for _ in range(20):
        pid.step(np.array([0.01, -0.01, 0.0]), np.zeros(3))
    # 20 steps of 0.1 s at 0.01 deg: 0.02 deg s, whichever law flew
    np.testing.assert_allclose(pid.integral, [0.02, -0.02, 0.0], atol=1e-15)
    pid.step(np.array([100.0, 0.0, np.nan]), np.zeros(3))   # saturated axis and NaN: held
    np.testing.assert_allclose(pid.integral, [0.02, -0.02, 0.0], atol=1e-15)


def test_registry_builds_the_twin_with_an_artifact_file(artifact, tmp_path):
    path = tmp_path / "a.json"
    artifact.save(path)
    c = build_controller("nn", torque_limit=1.0, control_period=0.1, artifact=str(path))
    out = c.step(measurement())
    assert isinstance(out, ControlOutput) and out.mode == "nn"


def test_golden_float32_follows_the_float64_twin(artifact):
    """Stated bound: A_bd within 0.5 arcsec and torque within 7.5e-3 N·m of the float64 twin on
    in-envelope vectors of the Table 5 pass moved across 2000-2100 (inputs rounded to float32)."""
    cfg = flight_config()
    rng = np.random.default_rng(3)
    n = 300
    scenario = StaringScenario()
    geo = scenario.geometry(rng, n)
    A, w = rng.uniform(-0.018, 0.018, (n, 3)) * DEG, rng.uniform(-0.0035, 0.0035, (n, 3)) * DEG
    inp = scenario.inputs(geo, A, w)
    out, _ = gc.step(artifact, cfg, gc.init(n), inp)
    twin = NnController(artifact, cfg)
    worst_A = worst_M = 0.0
    for i in range(n):
        twin.reset()
        m = Measurement(t=0.0, jd_days=int(geo.jd[i]), sec_of_day=float(inp["utc_ms"][i]) / 1000.0,
                        A_bo=inp["A_bo"][i].astype(float), omega_b=inp["omega_b"][i].astype(float),
                        R_s=inp["R_s"][i].astype(float), V_s=inp["V_s"][i].astype(float),
                        lon=float(inp["lon"][i]) * np.pi / 2**31, lat=float(inp["lat"][i]) * np.pi / 2**31)
        ref = twin.step(m)
        assert ref.mode == "nn" and out["status"][i] & ~np.uint32(cs.STATUS_SATURATED) == 0
        worst_A = max(worst_A, float(np.max(np.abs(out["A_bd"][i] - ref.info["A_bd"]))))
        worst_M = max(worst_M, float(np.max(np.abs(out["torque"][i] - ref.torque))))
    assert worst_A < 0.5 / 3600 * DEG, worst_A / DEG * 3600
    # the network's steepest input gain is ~54 N·m/deg (A_bd y): 0.5 arcsec -> 7.5e-3 N·m
    assert worst_M < 7.5e-3, worst_M


def test_closed_loop_twin_stays_on_the_network():
    c = build_controller("nn", torque_limit=1.0, control_period=0.1)
    h = simulate(c, TG.lon, TG.lat, SimConfig(duration=20.0))
    assert set(h.mode) == {"nn"}
    assert np.max(np.abs(h.A_bd[500:])) < 0.002 * DEG
