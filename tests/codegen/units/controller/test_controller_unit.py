"""The controller unit (paper 001 Fig. 2): golden == x86 C == ARM C bit for bit on the whole step,
time base accuracy, status bits, and a finite, limited torque for every input pattern. (What every
unit must do is in tests/codegen/units/test_every_unit.py; this file holds the controller's own.)"""
import json
import subprocess

import numpy as np
import pytest

from codegen.unit import Batch
from codegen.units.controller import golden as gc
from codegen.units.controller import spec as cs
from codegen.units.controller import vectors as cv
from codegen.units.controller.emit import INPUT_DTYPE, OUTPUT_DTYPE, STATE_DTYPE, controller_sources, to_bam
from codegen.units.controller.unit import ControllerUnit
from firmware import arm
from host.cli import main
from host.core.constants import ARCSEC, DEG
from host.control.nn_controller import flight_config, load_artifact
from host.sim.scenarios import StaringScenario
from host.core.timebase import gmst
from tools.gate import compare_fields
from tools.runners import arm_build, layout_checks, runner

N_STEPS = 4000
N_SEQ, SEQ_STEPS = 3, 1000


pytestmark = pytest.mark.usefixtures("private_cache")  # conftest: a build cache of its own


@pytest.fixture(scope="module")
def artifact():
    return load_artifact(None)


@pytest.fixture(scope="module")
def cfg():
    return flight_config()


@pytest.fixture(scope="module")
def scenario():
    return StaringScenario()


@pytest.fixture(scope="module")
def unit(artifact, cfg, scenario):
    return ControllerUnit(artifact, cfg, scenario)


@pytest.fixture(scope="module")
def vectors(unit):
    """(states, inputs, class index) of N_STEPS independent steps in the unit's gate classes."""
    classes = unit.gate_classes(N_STEPS, seed=11)
    kind = np.repeat(np.arange(len(classes)), [b.input.size for b in classes.values()])
    return (np.concatenate([b.state for b in classes.values()]), np.concatenate([b.input for b in classes.values()]),
            kind)


def on_targets(unit, states, inputs):
    """(outputs, states after) of the x86 and the ARM build."""
    return [runner(unit, t).records(Batch(states, inputs)) for t in ("x86", "arm")]


def same(g_out, g_state, out, st):
    return compare_fields(g_out, out) == [] and compare_fields(g_state, st) == []


def test_three_way_gate_independent_steps(unit, artifact, cfg, vectors):
    states, inputs, kind = vectors
    assert list(unit.gate_classes(100, 0)) == list(cv.KINDS)
    g_out, g_state = gc.step(artifact, cfg, states, inputs)
    for out, st in on_targets(unit, states, inputs):
        assert same(g_out, g_state, out, st)
        # uint32 patterns, every bit, on the torque itself
        assert np.array_equal(g_out["torque"].view(np.uint32), out["torque"].view(np.uint32))
    # every class exercised both laws
    pid = (g_out["status"] & cs.STATUS_PID) != 0
    assert 0 < pid[kind == 0].mean() < 1
    invalid = (g_out["status"] & cs.STATUS_INPUT_INVALID) != 0
    assert invalid[kind == 2].mean() > 0.3 and pid[invalid].all() and not invalid[kind == 0].any()


def test_corrupted_integrator_is_repaired_and_flagged(unit, artifact, cfg, vectors):
    """A NaN/Inf/huge integrator in the caller's state restarts at 0 with a status bit (all targets)."""
    _, inputs, kind = vectors
    rows = np.flatnonzero(kind == 0)[:len(cv.CORRUPT_INTEGRALS) * 3]
    states = gc.init(rows.size)
    states["mode"] = 1  # the PID flies: a silenced axis would show in the torque
    for k in range(rows.size):
        states["integral"][k, k % 3] = cv.CORRUPT_INTEGRALS[k // 3]
    g_out, g_state = gc.step(artifact, cfg, states, inputs[rows])
    assert np.all(g_out["status"] & cs.STATUS_STATE_REPAIRED)
    assert np.all(np.isfinite(g_out["torque"])) and np.all(np.abs(g_out["torque"]) <= cfg.torque_limit)
    assert np.all(np.abs(g_state["integral"]) <= cfg.integral_limit)
    for out, st in on_targets(unit, states, inputs[rows]):
        assert same(g_out, g_state, out, st)
    # healthy states never raise it
    healthy, _ = gc.step(artifact, cfg, gc.init(rows.size), inputs[rows])
    assert not np.any(healthy["status"] & cs.STATUS_STATE_REPAIRED)


def test_latitude_beyond_90_degrees_is_an_invalid_input(unit, artifact, cfg, vectors):
    """lat outside [-2^30, 2^30] (binary angle) would aim at the mirrored latitude: refused."""
    _, inputs, kind = vectors
    rows = np.flatnonzero(kind == 0)[:8]
    inp = inputs[rows].copy()
    inp["lat"] = np.where(np.arange(rows.size) % 2 == 0, cs.LAT_BAM_MAX + 1, -cs.LAT_BAM_MAX - 1)
    states = gc.init(rows.size)
    g_out, g_state = gc.step(artifact, cfg, states, inp)
    assert np.all(g_out["status"] & cs.STATUS_INPUT_INVALID) and np.all(g_out["status"] & cs.STATUS_PID)
    assert np.all(g_out["torque"] == 0.0)  # Table 1 PID on zeroed errors (Ki = 0)
    for out, st in on_targets(unit, states, inp):
        assert same(g_out, g_state, out, st)
    # exactly +-90 deg is a valid latitude
    inp["lat"] = np.where(np.arange(rows.size) % 2 == 0, cs.LAT_BAM_MAX, -cs.LAT_BAM_MAX)
    edge, _ = gc.step(artifact, cfg, states, inp)
    assert not np.any(edge["status"] & cs.STATUS_INPUT_INVALID)


def test_three_way_gate_sequences_with_mode_switches(unit):
    seqs = unit.gate_sequences(N_SEQ, SEQ_STEPS, seed=5)
    g = unit.golden_sequences(seqs)
    switches = np.sum(np.diff((g["status"] & cs.STATUS_PID) != 0, axis=1))
    assert switches >= 20
    x86, arm_ = runner(unit, "x86"), runner(unit, "arm")
    for s in range(N_SEQ):
        x86.reset()
        arm_.reset()
        assert compare_fields(g[s], x86.sequence(seqs[s])) == []
        assert compare_fields(g[s], arm_.sequence(seqs[s])) == []


def test_a_changed_operation_is_caught(artifact, cfg, vectors):
    """The gate can fail: a controller built with another PID gain differs from the golden model."""
    states, inputs, _ = vectors
    other = cfg.__class__(**{**cfg.__dict__, "kd": (46.0, 77.0, 50.5)})
    g_out, _ = gc.step(artifact, cfg, states, inputs)
    x_out, _ = runner(ControllerUnit(artifact, other), "x86").records(Batch(states, inputs))
    assert compare_fields(g_out, x_out) != []


def test_torque_finite_and_limited_for_special_values_in_every_field(unit, artifact, cfg, scenario):
    rng = np.random.default_rng(2)
    base = scenario.inputs(scenario.geometry(rng, 1), np.zeros((1, 3)), np.zeros((1, 3)))
    rows = []
    for f in cv.FLOAT_FIELDS:
        for i in range(3):
            for v in cv.SPECIAL_F32:
                r = base.copy()
                r[f][0, i] = v
                rows.append(r)
    for f in ("utc_day", "utc_ms", "lon", "lat"):
        for v in cv.INT_SPECIAL:
            r = base.copy()
            r[f] = np.int64(v).astype(np.int32) if f in ("lon", "lat") else np.clip(v, -2**31, 2**31 - 1)
            rows.append(r)
    bits = rng.integers(0, 2**32, (3000, INPUT_DTYPE.itemsize // 4), dtype=np.uint64).astype(np.uint32)
    inputs = np.concatenate([*rows, bits.view(INPUT_DTYPE).reshape(-1)])
    states = cv.random_states(rng, inputs.size, cfg.dwell_steps)
    g_out, _ = gc.step(artifact, cfg, states, inputs)
    x_out, _ = runner(unit, "x86").records(Batch(states, inputs))
    assert compare_fields(g_out, x_out) == []
    assert unit.check_outputs(x_out) == []
    invalid = (x_out["status"][:len(rows)] & cs.STATUS_INPUT_INVALID) != 0
    nonfinite = ~np.all(np.isfinite(np.stack([inputs[f][:len(rows)] for f in cv.FLOAT_FIELDS], 1).reshape(len(rows), -1)), 1)
    assert np.all(invalid[nonfinite])


def test_status_bits_name_the_crossed_bound(artifact, cfg, scenario):
    rng = np.random.default_rng(4)
    geo = scenario.geometry(rng, 6)
    A, w = np.zeros((6, 3)), np.zeros((6, 3))
    for k in range(6):
        (A if k < 3 else w)[k, k % 3] = (-1) ** k * (0.0202 if k < 3 else 0.00404) * DEG
    out, _ = gc.step(artifact, cfg, gc.init(6), scenario.inputs(geo, A, w))
    for k in range(6):
        assert out["status"][k] & cs.STATUS_BOUNDS_MASK == 1 << (cs.STATUS_BOUND_SHIFT + 6 + k)
        assert out["status"][k] & cs.STATUS_PID


def test_dwell_and_hand_back_in_the_c(unit, scenario):
    rng = np.random.default_rng(6)
    geo = scenario.geometry(rng, 1)
    clean = scenario.inputs(geo, np.zeros((1, 3)), np.zeros((1, 3)))
    bad = scenario.inputs(geo, np.array([[0.03 * DEG, 0, 0]]), np.zeros((1, 3)))
    seq = np.concatenate([clean, bad, *([clean] * 12)])
    c = runner(unit, "x86")
    c.reset()
    modes = (c.sequence(seq)["status"] & cs.STATUS_PID) != 0
    assert modes.tolist() == [False, True] + [True] * 9 + [False] * 3


def test_gmst_accurate_across_2000_2100():
    """The controller's integer GMST vs host.core.timebase.gmst (float64 IAU-82): < 0.001 arcsec."""
    rng = np.random.default_rng(0)
    day = np.concatenate([[0, 36524], rng.integers(0, 36525, 20000)])
    ms = np.concatenate([[0, 86_399_999], rng.integers(0, 86_400_000, 20000)])
    turns = gc.gmst_turns(day, ms).astype(np.float64) / 2**32
    ref = gmst(cs.J2000_JDN + day, ms / 1000.0) / (2 * np.pi)
    err = (turns - ref + 0.5) % 1.0 - 0.5
    assert np.max(np.abs(err)) * 2 * np.pi < 1e-3 * ARCSEC
    # and the float32 sine and cosine the step uses: the angle they encode is within 0.025 arcsec
    s, c = gc.sincos_turns(gc.gmst_turns(day, ms))
    ang = np.arctan2(s.astype(np.float64), c.astype(np.float64))
    d = (ang - ref * 2 * np.pi + np.pi) % (2 * np.pi) - np.pi
    assert np.max(np.abs(d)) < 0.025 * ARCSEC


def test_binary_angles_round_trip():
    lon = np.array([-np.pi, -1.0, 0.0, 2.0943951023931953, np.pi - 1e-9, np.pi])
    bam = to_bam(lon)
    assert bam[0] == -2**31 and bam[-1] == -2**31 and bam[2] == 0
    np.testing.assert_allclose(bam[1:5] * np.pi / 2**31, lon[1:5], atol=np.pi / 2**31)


def test_arm_image_has_no_soft_double_and_no_libm(unit):
    build = arm_build(unit, "sequence")
    arm.check_symbols(build.elf)
    names = subprocess.run([arm.tool(arm.ARM_NM), str(build.elf)], capture_output=True, text=True).stdout
    assert "__aeabi_d" not in names and "__aeabi_f2d" not in names and "__aeabi_l" not in names
    assert not build.newlib


def test_record_dtypes_are_the_c_structs(unit):
    """Sizes as documented; the cffi wrapper and the ARM adapters refuse to build otherwise."""
    assert (INPUT_DTYPE.itemsize, OUTPUT_DTYPE.itemsize, STATE_DTYPE.itemsize) == (64, 40, 24)
    checks = layout_checks(unit)
    assert "sizeof(controller_input_t) == 64u" in checks and "offsetof(controller_output_t, status) == 12u" in checks
    assert "offsetof(controller_input_t, lon) == 48u" in checks and "offsetof(controller_state_t, clean) == 16u" in checks


def test_sources_are_deterministic_and_share_the_network_templates(artifact, cfg):
    a, b = controller_sources(artifact, cfg), controller_sources(artifact, cfg)
    assert a == b
    assert set(a) == {"controller.h", "controller.c", "controller_nn.h", "controller_nn.c", "sg_math.h", "sg_math.c"}
    assert "controller_nn_eval(x, cmd)" in a["controller.c"] and "double" not in a["controller.c"]


def test_verify_and_cycles_commands(artifact, tmp_path, capsys):
    path = tmp_path / "a.json"
    artifact.save(path)
    assert main(["verify", "--unit", "controller", "--artifact", str(path), "--target", "all",
                 "--vectors", "600", "--sequences", "1"]) == 0
    assert "PASS" in capsys.readouterr().out
    report = tmp_path / "c.json"
    assert main(["cycles", "--unit", "controller", "--artifact", str(path), "--per-class", "4",
                 "--json", str(report)]) == 0
    rep = json.loads(report.read_text())["entries"]["controller"]
    assert set(rep["by_class"]) == {"nn_path", "pid_path", "dwell", "invalid", "bits"}
    # the PID path skips the network: far cheaper than the NN path
    assert rep["by_class"]["pid_path"]["ideal"]["max"] < rep["by_class"]["nn_path"]["ideal"]["min"] - 2000
    assert rep["stack_bytes"] <= 512 and rep["flash_bytes"] <= 24 * 1024
