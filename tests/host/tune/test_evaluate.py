"""`staregen evaluate`'s measures against analytic truth (a second-order step, a pure sine) and a
small end-to-end run whose PID staring row equals the batched simulator's."""
from __future__ import annotations

import math

import numpy as np
import pytest

from host.errors import HostError
from host.sim.batched import GainSets, simulate_pid_batch
from host.sim.simulator import SimConfig
from host.sim.targets import central_target, staring_targets
from host.tune.evaluate import (STEP_DEG, ControllerSpec, EvalPlan, evaluate, sine_amplitude, step_metrics,
                                table1_spec)


def test_step_metrics_of_an_underdamped_second_order_response():
    zeta, wn = 0.5, 2.0
    t = np.arange(0.0, 60.0, 0.01)
    tau = np.clip(t - 30.0, 0.0, None)
    wd = wn * math.sqrt(1 - zeta ** 2)
    y = 1 - np.exp(-zeta * wn * tau) * (np.cos(wd * tau) + zeta / math.sqrt(1 - zeta ** 2) * np.sin(wd * tau))
    d = -STEP_DEG * np.repeat(y[:, None], 3, 1)
    m = step_metrics(d, t)
    overshoot = 100 * math.exp(-zeta * math.pi / math.sqrt(1 - zeta ** 2))      # 16.3 %
    assert m["overshoot_pct"] == pytest.approx([overshoot] * 3, abs=0.01)
    # last exit from the 5 % band: the envelope bound 1 + e^{-zeta wn t}/sqrt(1-zeta^2) = 1.05 gives an
    # upper limit; the true last exit is at or before it
    bound = -math.log(0.05 * math.sqrt(1 - zeta ** 2)) / (zeta * wn)
    assert all(2.0 < s <= bound + 0.01 for s in m["settling_s"])
    assert m["steady_state_deg"] == pytest.approx([0.0] * 3, abs=1e-9)


def test_step_metrics_of_a_biased_first_order_response():
    t = np.arange(0.0, 80.0, 0.1)
    tau = np.clip(t - 30.0, 0.0, None)
    d = -0.9 * STEP_DEG * (1 - np.exp(-tau / 2.0))
    m = step_metrics(np.repeat(d[:, None], 3, 1), t)
    assert m["overshoot_pct"] == [0.0] * 3
    assert m["steady_state_deg"] == pytest.approx([0.1 * STEP_DEG] * 3, rel=1e-6)
    assert m["settling_s"] == pytest.approx([50.0 - 0.1] * 3, abs=0.11)    # never inside the band: to the end


def test_sine_amplitude_recovers_a_sine_with_offset_and_noise():
    t = np.arange(20.0, 60.0, 0.1)
    rng = np.random.default_rng(0)
    d = 3e-4 * np.sin(2 * np.pi * 0.7 * t + 0.4) + 1e-3 + rng.normal(0, 1e-6, t.size)
    assert sine_amplitude(d, t, 0.7) == pytest.approx(3e-4, rel=1e-3)


def test_plan_validation():
    c = central_target()
    one = ((c.name, c.lon, c.lat, 0),)
    with pytest.raises(HostError, match="Nyquist"):
        EvalPlan(one, one, one[0], freqs=(6.0,))
    with pytest.raises(HostError, match="at least one target"):
        EvalPlan((), one, one[0])
    with pytest.raises(HostError, match="step response"):
        EvalPlan(one, one, one[0], step_duration=40.0)


def test_small_run_pid_row_equals_the_batched_simulator():
    ts = staring_targets()[:2]
    tg = tuple((t.name, t.lon, t.lat, i) for i, t in enumerate(ts))
    plan = EvalPlan(tg, tg[:1], tg[0], duration=12.0, step_duration=45.0, freqs=(1.0,), freq_duration=30.0)
    r = evaluate(plan, [table1_spec()], workers=1, progress=False)
    g = table1_spec().gains
    res = simulate_pid_batch([(t.lon, t.lat) for t in ts], GainSets.single(g.kp, g.ki, g.kd), (0,),
                             SimConfig(duration=12.0))
    row = r["staring"]["PID (Table 1)"]
    assert row["J"] == pytest.approx(float(res.J().mean()), rel=1e-12) and row["targets"] == 2
    step = r["step"]["PID (Table 1)"]["mean"]
    assert all(0.0 < s < 15.0 for s in step["settling_s"]) and all(e < 0.5 * STEP_DEG for e in step["steady_state_deg"])
    amp = np.array(r["frequency"]["PID (Table 1)"]["amplitude_deg"])
    assert amp.shape == (3, 1) and np.all(amp > 0)
    with pytest.raises(HostError, match="twice"):
        evaluate(plan, [table1_spec(), table1_spec()], workers=1, progress=False)


def test_the_batched_and_the_scalar_engine_give_the_same_evaluation(artifact_file):
    """Every experiment through both engines: the staring rows, the step metrics and the frequency
    amplitudes of the PID and the network agree (1e-9 relative on J; the responses to 1e-9°)."""
    c = central_target()
    targets = tuple((t.name, t.lon, t.lat, i) for i, t in enumerate(staring_targets()[:1]))
    specs = [table1_spec(), ControllerSpec("NN (float64)", "nn", (("artifact", artifact_file),))]
    runs = {}
    for engine in ("batched", "scalar"):
        plan = EvalPlan(targets=targets, response_targets=targets[:1], central=(c.name, c.lon, c.lat, 0),
                        duration=12.0, step_duration=45.0, freqs=(0.5,), freq_duration=30.0, engine=engine)
        runs[engine] = evaluate(plan, specs, workers=1, progress=False)
    b, s = runs["batched"], runs["scalar"]
    for table in ("staring", "staring_central"):
        for label in b[table]:
            assert abs(b[table][label]["J"] - s[table][label]["J"]) <= 1e-9 * s[table][label]["J"], (table, label)
    for label in b["step"]:
        np.testing.assert_allclose(b["step"][label]["first_target_response_deg"],
                                   s["step"][label]["first_target_response_deg"], rtol=0, atol=1e-9)
        np.testing.assert_allclose(b["frequency"][label]["amplitude_deg"], s["frequency"][label]["amplitude_deg"],
                                   rtol=1e-6, atol=1e-12)
    assert b["plan"]["engine"] == "batched" and s["plan"]["engine"] == "scalar"
