"""The generated controller in the loop (host.control.generated_controller through tools.inloop): SIL (x86) and
PIL (emulated Cortex-M4) vs the float64 twin, and step for step against the golden model."""
import numpy as np
import pytest

from codegen.units.controller import spec as cs
from codegen.units.controller.unit import ControllerUnit
from host.cli import main
from host.control.generated_controller import GeneratedController
from host.control.controllers import build_controller
from host.sim.metrics import staring_metrics
from host.control.nn_controller import flight_config, load_artifact
from host.sim.simulator import SimConfig, simulate
from host.sim.targets import central_target
from tools.gate import compare_fields

TG = central_target()
DURATION = 100.0


pytestmark = pytest.mark.usefixtures("private_cache")


def fly(name: str, artifact_file: str | None, duration: float = DURATION):
    opts = {"artifact": artifact_file} if artifact_file else {}
    c = build_controller(name, torque_limit=1.0, control_period=0.1, **opts)
    h = simulate(c, TG.lon, TG.lat, SimConfig(duration=duration))
    return c, h, staring_metrics(h.t, h.A_bd, h.omega_e, t_end=duration)


def assert_within_1pct(m, ref):
    for key in ("J_A", "J_w", "J"):
        rel = abs(getattr(m, key) / getattr(ref, key) - 1.0)
        assert rel < 0.01, (key, rel)


@pytest.fixture(scope="module")
def twin_run(artifact_file):
    return fly("nn", artifact_file)


@pytest.fixture(scope="module")
def sil_run(artifact_file):
    return fly("nn-c", artifact_file)


def test_sil_matches_the_float64_twin_within_1_percent(twin_run, sil_run):
    _, h_twin, m_twin = twin_run
    _, h_sil, m_sil = sil_run
    assert set(h_sil.mode) == {"nn"} == set(h_twin.mode)
    assert_within_1pct(m_sil, m_twin)


def test_sil_steps_equal_the_golden_model_bit_for_bit(artifact_file, sil_run):
    c, _, _ = sil_run
    inputs, outputs = c.loop.trace()
    assert inputs.size == int(DURATION / 0.1)
    golden = ControllerUnit(load_artifact(artifact_file), flight_config()).golden_sequences(inputs[None, :])[0]
    assert compare_fields(golden, outputs) == []


def test_pid_c_matches_the_float64_pid_within_1_percent(artifact_file):
    _, h_ref, m_ref = fly("pid", None)
    c, h, m = fly("pid-c", artifact_file)
    assert set(h.mode) == {"pid"}
    assert np.all(c.loop.trace()[1]["status"] & cs.STATUS_PID)
    assert_within_1pct(m, m_ref)


def test_pil_equals_sil_step_for_step_and_records_cycles(artifact_file, sil_run):
    duration = 30.0
    c_pil, h_pil, _ = fly("nn-arm", artifact_file, duration)
    sil_in, sil_out = sil_run[0].loop.trace()
    pil_in, pil_out = c_pil.loop.trace()
    n = pil_in.size
    assert n == int(duration / 0.1)
    # same closed loop: identical inputs, identical outputs, at every step
    assert np.array_equal(pil_in.view(np.uint8), sil_in[:n].view(np.uint8))
    assert compare_fields(sil_out[:n], pil_out) == []
    cycles = np.array(c_pil.loop.cycles)
    assert cycles.size == n and 2_000 < cycles.min() and cycles.max() < 20_000


def test_simulate_cli_runs_the_generated_controller(artifact_file, tmp_path, capsys):
    out = tmp_path / "sil"
    assert main(["simulate", "--controller", "nn-c", "--artifact", artifact_file, "--duration", "12",
                 "--out", str(out)]) == 0
    assert (out / "metrics.json").is_file() and "controller nn-c" in capsys.readouterr().out
    assert main(["simulate", "--controller", "pid", "--artifact", artifact_file, "--duration", "12",
                 "--out", str(tmp_path / "p")]) == 2   # --artifact applies to network controllers only


def test_the_golden_twin_compares_every_step_when_asked(artifact_file):
    """golden_twin=True: tools.inloop steps the golden model alongside and counts differing steps."""
    unit = ControllerUnit(load_artifact(artifact_file), flight_config())
    c = GeneratedController(unit, "x86", "nn-c", golden_twin=True)
    simulate(c, TG.lon, TG.lat, SimConfig(duration=5.0))
    assert len(c.loop.outputs) == int(5.0 / 0.1) and c.loop.twin is not None
    assert c.loop.mismatch_steps == 0
