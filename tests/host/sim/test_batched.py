"""The batched simulator against the scalar reference (host.sim.simulator): J_A, J_ω and J of
every scenario equal to 1e-9 relative, including step-response (attitude offset) and
frequency-response (per-scenario periodic torque) scenarios; common random numbers."""
from __future__ import annotations

import numpy as np
import pytest

from host.control.pid import PidController, PidGains
from host.core.constants import DEG
from host.errors import HostError
from host.sim.batched import GainSets, simulate_pid_batch
from host.sim.metrics import staring_metrics
from host.sim.simulator import SimConfig, simulate
from host.sim.targets import staring_targets

DURATION = 16.0
REL = 1e-9


def _scalar(target, gains: PidGains, seed: int, stream: int, **extra):
    cfg = SimConfig(duration=DURATION, seed=seed, **extra)
    h = simulate(PidController(gains, cfg.spacecraft.torque_limit, cfg.control_period),
                 target.lon, target.lat, cfg, stream=stream)
    return staring_metrics(h.t, h.A_bd, h.omega_e, t_end=DURATION)


def _assert_close(batch, scalar, where):
    for name in ("J_A", "J_w", "J"):
        b, s = float(batch[name]), getattr(scalar, name)
        assert abs(b - s) <= REL * abs(s), f"{where}: {name} batched {b!r} scalar {s!r}"


def _gains(rng, g):
    kp = rng.uniform(1.0, 60.0, (g, 3))
    ki = rng.choice([0.0, 0.01, 0.03], (g, 3))
    kd = rng.uniform(40.0, 90.0, (g, 3))
    kp[0], ki[0], kd[0] = PidGains().kp, PidGains().ki, PidGains().kd     # Table 1
    return GainSets(kp, ki, kd)


def test_random_scenarios_equal_the_scalar_simulator():
    rng = np.random.default_rng(7)
    all_targets = staring_targets()
    picks = rng.choice(len(all_targets), 3, replace=False)
    targets = [all_targets[i] for i in picks]
    gains, seeds = _gains(rng, 4), (0, 11)
    res = simulate_pid_batch([(t.lon, t.lat) for t in targets], gains, seeds, SimConfig(duration=DURATION),
                             streams=[int(i) for i in picks])
    J = {"J_A": res.J_A, "J_w": res.J_w, "J": res.J()}
    checked = 0
    for ti, tg in enumerate(targets):
        for gi in range(len(gains)):
            for si, seed in enumerate(seeds):
                s = _scalar(tg, PidGains(gains.kp[gi], gains.ki[gi], gains.kd[gi]), seed, int(picks[ti]))
                _assert_close({k: v[ti, gi, si] for k, v in J.items()}, s, f"target {picks[ti]} gains {gi} seed {seed}")
                checked += 1
    assert checked >= 20


def test_step_and_frequency_response_scenarios_equal_the_scalar_simulator():
    targets = staring_targets()[:2]
    gains = GainSets.single(PidGains().kp, PidGains().ki, PidGains().kd)

    def offset(t):
        return np.full(3, 0.005 * DEG) if t >= 12.0 else np.zeros(3)
    res = simulate_pid_batch([(t.lon, t.lat) for t in targets], gains, (0,),
                             SimConfig(duration=DURATION, attitude_offset=offset))
    for ti, tg in enumerate(targets):
        s = _scalar(tg, PidGains(), 0, ti, attitude_offset=offset)
        _assert_close({"J_A": res.J_A[ti, 0, 0], "J_w": res.J_w[ti, 0, 0], "J": res.J()[ti, 0, 0]}, s, "step")

    freqs = np.array([0.05, 0.5, 2.0])                 # Hz, one per gain-set row (the same gains)
    many = GainSets(np.repeat(gains.kp, 3, 0), np.repeat(gains.ki, 3, 0), np.repeat(gains.kd, 3, 0))

    def torque(t):   # (T·G·N, 3): target-major, then gain set (= frequency)
        return np.tile(np.repeat(0.03 * np.sin(2 * np.pi * freqs * t)[:, None], 3, 1), (len(targets), 1))
    res = simulate_pid_batch([(t.lon, t.lat) for t in targets], many, (0,),
                             SimConfig(duration=DURATION, extra_torque=torque))
    for ti, tg in enumerate(targets):
        for fi, f in enumerate(freqs):
            def one(t, f=f):
                return np.full(3, 0.03 * np.sin(2 * np.pi * f * t))
            s = _scalar(tg, PidGains(), 0, ti, extra_torque=one)
            _assert_close({"J_A": res.J_A[ti, fi, 0], "J_w": res.J_w[ti, fi, 0], "J": res.J()[ti, fi, 0]}, s,
                          f"frequency {f} Hz")


def test_a_scenario_does_not_depend_on_its_batch_neighbours():
    tg = staring_targets()[5]
    rng = np.random.default_rng(3)
    gains = _gains(rng, 5)
    together = simulate_pid_batch([(tg.lon, tg.lat)], gains, (2,), SimConfig(duration=12.0), streams=[5])
    alone = simulate_pid_batch([(tg.lon, tg.lat)], GainSets.single(gains.kp[3], gains.ki[3], gains.kd[3]), (2,),
                               SimConfig(duration=12.0), streams=[5])
    assert abs(together.J()[0, 3, 0] - alone.J()[0, 0, 0]) <= 1e-12 * alone.J()[0, 0, 0]
    assert together.J_A_axis.shape == (1, 5, 1, 3)
    assert np.allclose(together.J_axis().mean(-1), together.J(), rtol=1e-14, atol=0)


@pytest.mark.parametrize("kwargs, message", [
    ({"gains": GainSets(np.zeros((0, 3)), np.zeros((0, 3)), np.zeros((0, 3)))}, "at least one"),
    ({"seeds": ()}, "at least one"),
    ({"streams": [0, 1]}, "noise streams"),
])
def test_bad_batches_are_one_line_errors(kwargs, message):
    args = {"targets": [(staring_targets()[0].lon, staring_targets()[0].lat)],
            "gains": GainSets.single([1, 1, 1], [0, 0, 0], [40, 40, 40]), "seeds": (0,),
            "config": SimConfig(duration=11.0)}
    args.update(kwargs)
    with pytest.raises(HostError, match=message):
        simulate_pid_batch(**args)


def test_gain_sets_are_validated():
    with pytest.raises(HostError, match=r"\(G, 3\)"):
        GainSets(np.zeros((2, 3)), np.zeros((2, 2)), np.zeros((2, 3)))
    with pytest.raises(HostError, match="non-finite"):
        GainSets.single([np.nan, 1, 1], [0, 0, 0], [1, 1, 1])
