"""Paper 004's closed loop and data: the baseline's spring fight with the target (its equilibrium solved
independently and held; the wheels take the counter-torque for ever), the GP law with an oracle mean
removes the offset, 300 s runs from the capture state, and section 3's data collection."""
import numpy as np
import pytest
from scipy.optimize import fsolve

from host.control.takeover_laws import BaselineLaw, GpLaw
from host.core.constants import DEG
from host.errors import HostError
from host.plant import takeover as tk
from host.plant.error_model import TABLE6_ERRORS
from host.plant.spacecraft import pack_state
from host.sim import takeover as st

PLANT = tk.TakeoverPlant()


class Oracle:
    """A perfect GP: mean = d₀ = τ_t − ω×(ΔJ ω) (d at ω̇ = 0) from the truth model, variance 0."""

    def predict(self, x):
        q = np.concatenate([x[:3], [np.sqrt(1.0 - x[:3] @ x[:3])]])
        return PLANT.unknown_term_at_rest_acceleration(q, x[3:6]), np.zeros(3)


def baseline_equilibrium():
    """At rest the baseline balances the target: −k1 q_v + τ_t(q, 0) = 0 (solved here, not simulated)."""
    def residual(v):
        q = np.concatenate([v, [np.sqrt(1.0 - v @ v)]])
        return -4.0 * v + tk.counter_torque(q, np.zeros(3), PLANT.q_t0)
    v = fsolve(residual, 0.1 * PLANT.q_t0[:3], xtol=1e-12)
    return np.concatenate([v, [np.sqrt(1.0 - v @ v)]])


def test_baseline_equilibrium_is_the_doc_estimate_and_the_loop_holds_it():
    q_eq = baseline_equilibrium()
    angle = st.error_angle(q_eq) / DEG
    assert angle == pytest.approx(20.0 * 0.5 / 4.5, rel=0.01)       # doc: K_pt/(k1 + K_pt) · 20° ≈ 2.2°
    hist = st.simulate(st.law_controller(BaselineLaw()), 20.0, PLANT, pack_state(q_eq, np.zeros(3), np.zeros(3)))
    assert np.max(np.abs(hist["angle"] / DEG - angle)) < 1e-6
    # the fight never ends: the wheels take the counter-torque, ḣ_w = −u = τ_t
    slope = (hist["h_w"][-1] - hist["h_w"][0]) / hist["t"][-1]
    np.testing.assert_allclose(slope, tk.counter_torque(q_eq, np.zeros(3), PLANT.q_t0), rtol=1e-6)


def test_oracle_gp_law_holds_the_reference_against_the_target():
    x0 = pack_state([0.0, 0.0, 0.0, 1.0], np.zeros(3), np.zeros(3))
    law = GpLaw(Oracle(), prior_variance=np.ones(3))
    hist = st.simulate(st.law_controller(law), 20.0, PLANT, x0)
    assert np.max(hist["angle"]) < 1e-9
    np.testing.assert_array_equal(hist["gains"][:-1], np.tile([4.0, 72.0], (len(hist["t"]) - 1, 1)))


def _run_300s(law):
    hist = st.simulate(st.law_controller(law), 300.0, PLANT)
    return hist, st.metrics_of(hist, PLANT)


@pytest.fixture(scope="module")
def baseline_run():
    return _run_300s(BaselineLaw())


@pytest.fixture(scope="module")
def oracle_run():
    return _run_300s(GpLaw(Oracle(), prior_variance=np.ones(3)))


@pytest.fixture
def runs(baseline_run, oracle_run):
    return {"baseline": baseline_run, "oracle": oracle_run}


def test_baseline_stabilises_into_the_offset(baseline_run):
    hist, m = baseline_run
    assert m["finite"]
    eq = st.error_angle(baseline_equilibrium()) / DEG
    # measured: 2.46° mean over 240-300 s, still closing on the 2.21° equilibrium from above
    assert eq < m["steady_error_deg_mean"] < eq + 0.5
    assert np.max(np.linalg.norm(hist["omega"][-600:], axis=1)) < 0.01 * DEG
    assert m["t_settle_1deg"] is None                     # it never gets within 1°


def test_oracle_gp_removes_most_of_the_offset(runs):
    """The oracle cancels τ_t − ω×ΔJω exactly, leaving J_c ω̇ = −K1 q_v − K2 ω: no bias, only the PD's slow
    tail (measured 0.34° mean over 240-300 s; the peak per minute falls 3.0° → 2.0° → 0.40° over 120-300 s,
    an oscillating decay: ζ ≈ 0.5 on the heavy axes). Tolerance: below a quarter of the baseline's error (measured
    0.14×) and the last minute's peak under half the previous minute's (measured 0.20×); the equilibrium itself is
    0 (test_oracle_gp_law_holds_the_reference_against_the_target)."""
    _, base = runs["baseline"]
    hist, m = runs["oracle"]
    assert m["steady_error_deg_mean"] < 0.25 * base["steady_error_deg_mean"]
    assert m["t_settle_1deg"] is not None and m["t_settle_1deg"] < 240.0
    t, angle = hist["t"], hist["angle"]
    assert np.max(angle[t >= 240.0]) < 0.5 * np.max(angle[(t >= 180.0) & (t < 240.0)])


def test_wheel_momentum_after_300s_stays_below_the_limit_and_grows(runs):
    for name in ("baseline", "oracle"):
        hist, m = runs[name]
        assert max(m["max_abs_h_w"]) < PLANT.momentum_limit
        # the body's initial momentum J_c ω(0) went into the wheels, same signs, then τ_t keeps adding
        H0 = PLANT.inertia @ tk.CAPTURE_RATE
        assert np.all(np.sign(hist["h_w"][-1]) == np.sign(H0))
        assert all(t is not None and 300.0 < t < 2000.0 for t in m["t_momentum_limit"])


def test_simulate_refuses_bad_durations():
    for bad in (0.0, -1.0, float("nan"), "10"):
        with pytest.raises(HostError, match="duration"):
            st.simulate(st.law_controller(BaselineLaw()), bad)


# ----------------------------------------------------------------------------- section 3 data

DATA_DURATION = 120.0


@pytest.fixture(scope="module")
def one_run():
    exc = st.Excitation(5, DATA_DURATION)
    hist = st.simulate(exc, DATA_DURATION, PLANT, tk.capture_state(PLANT, omega0=exc.initial_rate))
    return hist, st.samples_of(hist, PLANT.prior_inertia)


def test_collect_shapes_and_determinism(one_run):
    data = st.collect([5], DATA_DURATION)
    n = int(DATA_DURATION) - 1                             # t = 1 .. duration − 1
    assert data["x"].shape == (n, 9) and data["d"].shape == (n, 3)
    assert data["u"].shape == (n, 3) and data["h_w"].shape == (n, 3)
    np.testing.assert_allclose(data["t"], np.arange(1.0, DATA_DURATION))
    np.testing.assert_array_equal(data["x"], one_run[1]["x"])
    assert np.all(np.abs(data["u"]) <= 1.0)
    assert np.all(np.linalg.norm(data["x"][:, :3], axis=1) < 1.0)


def test_central_difference_is_within_the_window_range_of_the_true_acceleration(one_run):
    """The central difference is the window mean of ω̇, so it lies between the window's smallest and largest
    ω̇ (truth, sampled at the control instants; slack for the variation inside a period), as does ω̇(t)."""
    hist, s = one_run
    cd, truth = s["x"][:, 6:9], s["omega_dot_true"]
    for i, t in enumerate(s["t"]):
        k = int(round(t / 0.1))
        win = hist["omega_dot"][k - 5:k + 5]
        slack = 2e-6
        assert np.all(cd[i] >= win.min(axis=0) - slack) and np.all(cd[i] <= win.max(axis=0) + slack)
    # and on the whole the window error is small: RMS below 25 % of the RMS acceleration (measured 11-17 %
    # over 300 s, from the 0.1 s command steps and the setpoint jumps)
    err = np.sqrt(np.mean((cd - truth) ** 2, axis=0))
    assert np.all(err < 0.25 * np.sqrt(np.mean(truth ** 2, axis=0)))


def test_sampled_d_matches_the_truths_d_to_the_window_error(one_run):
    _, s = one_run
    err = np.sqrt(np.mean((s["d"] - s["d_true"]) ** 2, axis=0))
    assert np.all(err < 0.25 * np.sqrt(np.mean(s["d_true"] ** 2, axis=0)))


def test_excitation_is_seeded_and_stays_in_the_doc_ranges():
    a, b = st.Excitation(3), st.Excitation(3)
    np.testing.assert_array_equal(a.initial_rate, b.initial_rate)
    assert np.all(np.abs(a.initial_rate) <= 0.6 * DEG)
    assert all(st.error_angle(q) <= 25.0 * DEG + 1e-12 for q in a.setpoints)
    t = np.linspace(0, 300, 3001)
    amp = np.max(np.abs([a.multisine(ti) for ti in t]))
    assert amp <= 5 * 0.06 + 1e-12


def test_collect_refuses_bad_seeds():
    for bad in ([], [-1], [1.5], ["a"]):
        with pytest.raises(HostError, match="seeds"):
            st.collect(bad, 10.0)


# ----------------------------------------------------------------------------- Table 6 errors


def test_table6_errors_reach_the_controller_and_the_wheels():
    seen = []

    def spy(t, q, w, hw):
        seen.append((q, w))
        return BaselineLaw()(q, w, hw)

    hist = st.simulate(spy, 10.0, PLANT, errors=TABLE6_ERRORS, seed=4)
    # the controller saw the measured values, not the truth
    np.testing.assert_array_equal(seen[3][0], hist["q_meas"][3])
    # star sensor: a small rotation of about |3″ bias + 1″ noise| per axis (≈ 5″), never 20″
    q_err = np.array([tk.error_quat(a, b) for a, b in zip(hist["q_meas"], hist["q"])])
    ang = 2 * np.arcsin(np.linalg.norm(q_err[:, :3], axis=1)) / (DEG / 3600)
    assert 1.0 < np.mean(ang) < 10.0 and np.max(ang) < 20.0
    # gyro: the bias 0.15 °/h on average (noise σ 0.15 °/h over 101 draws: mean within 0.06 °/h)
    bias = np.mean(hist["omega_meas"] - hist["omega"], axis=0) / (DEG / 3600)
    np.testing.assert_allclose(bias, 0.15, atol=0.06)
    # wheels: (u + 0.01) + N(0, 0.01) per period: the mean excess is the bias within 4σ/√100
    excess = np.mean(hist["torque_applied"][:-1] - hist["torque_known"][:-1], axis=0)
    np.testing.assert_allclose(excess, 0.01, atol=0.004)


def test_errors_are_seeded():
    a = st.simulate(st.law_controller(BaselineLaw()), 2.0, PLANT, errors=TABLE6_ERRORS, seed=1)
    b = st.simulate(st.law_controller(BaselineLaw()), 2.0, PLANT, errors=TABLE6_ERRORS, seed=1)
    c = st.simulate(st.law_controller(BaselineLaw()), 2.0, PLANT, errors=TABLE6_ERRORS, seed=2)
    np.testing.assert_array_equal(a["q_meas"], b["q_meas"])
    assert not np.array_equal(a["q_meas"], c["q_meas"])


def test_collect_with_errors_learns_the_wheel_bias_into_d():
    """With the wheel bias acting and unknown to the servicer, the sampled d = truth's d − bias on average
    (the truth's d uses the applied torque, which includes it)."""
    data = st.collect([2], 30.0, errors=TABLE6_ERRORS)
    assert data["x"].shape == (29, 9)
    offset = np.mean(data["d_true"] - data["d"], axis=0)
    np.testing.assert_allclose(offset, -0.01, atol=0.005)


def test_momentum_limit_time_of_a_linear_ramp():
    t = np.arange(0.0, 301.0)
    h = np.stack([10.0 + 0.05 * t, -5.0 - 0.1 * t, 3.5 - 0.01 * t], axis=1)   # z shrinking towards 0 (0.5 at the end)
    out = st.momentum_limit_time(t, h, 50.0)
    assert out[0] == pytest.approx(300.0 + (50.0 - 25.0) / 0.05)
    assert out[1] == pytest.approx(300.0 + (50.0 - 35.0) / 0.1)
    assert out[2] is None
