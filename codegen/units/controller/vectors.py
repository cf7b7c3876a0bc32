"""Gate and cycle input classes of the generated controller, over a host-supplied flight scenario.

Realistic inputs need the orbit, the Earth and the staring guidance, which live in the host
(codegen knows nothing of the simulator): a `FlightScenario` (host.sim.scenarios implements
it) turns geometry samples and chosen errors in S_d into sensor readings. The classes:
  inside    errors uniform inside Table 2, random controller states (either mode, any dwell count);
  bound     one of A_bd / ω_e at a bound ×(1 ± 1e-3), or a target far off-track (ω_d bounds);
            an eighth with the body y axis along ± the desired z axis (a 90° roll error: the
            asin argument rounds beyond ±1 in about a sixth of them and its clamp runs);
  invalid   one field (or all) of the input set to NaN, ±Inf, ±FLT_MAX, ±0, subnormals; UTC
            day or ms out of range;
  bits      every field a random bit pattern.
Sequences: S runs of T consecutive 0.1 s steps from init, errors oscillating across the envelope
(mode switches and dwells), with bursts of NaN inputs. Cycle classes (state in the record):
nn_path, pid_path, dwell, invalid, bits.
"""
from __future__ import annotations

import math
from typing import NamedTuple, Protocol

import numpy as np

from codegen.unit import Batch
from codegen.golden_vec3 import v_dot
from codegen.units.controller import golden as cg
from codegen.units.controller import spec as cs
from codegen.units.controller.emit import INPUT_DTYPE, STATE_DTYPE

KINDS = ("inside", "bound", "invalid", "bits")
SHARES = {"bound": 0.2, "invalid": 0.15, "bits": 0.05}   # inside takes the rest
DEG = math.pi / 180.0
A_BOUND_DEG, W_BOUND_DEG = 0.02, 0.004                   # Table 2 attitude / rate error bounds


class Geometry(NamedTuple):
    """Where the satellite and its target are (float64, one row per step)."""

    jd: np.ndarray      # Julian Day Number of the UTC day
    sec: np.ndarray     # s of that day
    R: np.ndarray       # (n, 3) ECI position, m
    V: np.ndarray       # (n, 3) ECI velocity, m/s
    lon: np.ndarray     # target geodetic longitude, rad
    lat: np.ndarray     # target geodetic latitude, rad


class FlightScenario(Protocol):
    """Host-side source of realistic controller inputs."""

    def geometry(self, rng: np.random.Generator, n: int, far_targets: bool = False) -> Geometry:
        """n samples of a staring pass at random instants, random UTC in 2000-2100."""

    def sequence_geometry(self, rng: np.random.Generator, steps: int) -> Geometry:
        """`steps` consecutive 0.1 s steps of a pass over one target."""

    def inputs(self, g: Geometry, A_bd: np.ndarray, omega_e: np.ndarray) -> np.ndarray:
        """INPUT_DTYPE records whose attitude / rate errors in S_d are A_bd (rad), omega_e (rad/s)."""


CORRUPT_INTEGRALS = np.array([np.nan, np.inf, -np.inf, 3.4028235e38, -1e6, 1e6], dtype=np.float32)
CORRUPT_SHARE = 0.02
FAULT_SHARE = 0.02
NEAR_LIMIT_SHARE = 0.05   # integrators within 0.004 deg*s of the limit (the clamp runs)     # states whose integrity check failed (the step must fly the PID)
SPECIAL_F32 = np.array([np.nan, -np.nan, np.inf, -np.inf, np.finfo(np.float32).max, -np.finfo(np.float32).max,
                        0.0, -0.0, 1e-45, -1e-45, 1.1754942e-38], dtype=np.float32)
FLOAT_FIELDS = ("A_bo", "omega_b", "R_s", "V_s")
INT_SPECIAL = np.array([-2**31, -1, 0, 2**31 - 1, cs.UTC_MS_MAX, cs.UTC_DAY_MAX + 1, cs.UTC_DAY_MIN - 1],
                       dtype=np.int64)


def random_states(rng: np.random.Generator, n: int, dwell: int) -> np.ndarray:
    """Reachable states, plus a few corrupted integrators (bit flips) that the step must repair."""
    st = np.zeros(n, dtype=STATE_DTYPE)
    st["integral"] = rng.uniform(-1.0, 1.0, (n, 3))
    st["mode"] = rng.integers(0, 2, n)
    st["clean"] = rng.integers(0, dwell + 1, n)
    bad = np.flatnonzero(rng.random(n) < CORRUPT_SHARE)
    st["integral"][bad, rng.integers(0, 3, bad.size)] = rng.choice(CORRUPT_INTEGRALS, bad.size)
    st["fault"] = np.where(rng.random(n) < FAULT_SHARE, rng.choice([1, 0xFFFFFFFF], n), 0)   # a failed CRC
    return st


def uniform_errors(rng, n, scale=1.0):
    """(A_bd [rad], ω_e [rad/s]) uniform in scale × the Table 2 error bounds, (n, 3) each."""
    return (rng.uniform(-A_BOUND_DEG, A_BOUND_DEG, (n, 3)) * scale * DEG,
            rng.uniform(-W_BOUND_DEG, W_BOUND_DEG, (n, 3)) * scale * DEG)


def inside_inputs(sc: FlightScenario, rng, n, scale=0.95):
    return sc.inputs(sc.geometry(rng, n), *uniform_errors(rng, n, scale))


def bound_inputs(sc: FlightScenario, rng, n):
    """Half: one attitude or rate error at a bound ×(1 ± 1e-3); half: targets far off-track."""
    A, w = uniform_errors(rng, n, 0.9)
    half = n // 2
    rows = np.arange(half)
    col = rng.integers(0, 6, half)
    side = rng.choice([-1.0, 1.0], half)
    factor = 1.0 + rng.choice([-1e-3, 1e-3], half)
    A[rows[col < 3], col[col < 3]] = (side * factor * A_BOUND_DEG * DEG)[col < 3]
    w[rows[col >= 3], col[col >= 3] - 3] = (side * factor * W_BOUND_DEG * DEG)[col >= 3]
    g_near = sc.geometry(rng, half)
    g_far = sc.geometry(rng, n - half, far_targets=True)
    return np.concatenate([sc.inputs(g_near, A[:half], w[:half]), sc.inputs(g_far, A[half:], w[half:])])


def parallel_axis_attitudes(cfg: cs.ControllerConfig, inp: np.ndarray, rng) -> np.ndarray:
    """A_bo (rad, float32) putting the body y axis along ± the desired z axis of each row: the
    controller's s = b1 . c2 (the sine of the roll error) is then ±1 up to rounding."""
    R = tuple(np.ascontiguousarray(inp["R_s"][:, i]) for i in range(3))
    V = tuple(np.ascontiguousarray(inp["V_s"][:, i]) for i in range(3))
    d = cg.desired(cfg, R, V, cg.target(cfg, inp["lon"], inp["lat"], cg.gmst_turns(inp["utc_day"], inp["utc_ms"])))
    c2 = np.stack([v_dot(d["xo"], d["z"]), -v_dot(d["n"], d["z"]), -v_dot(d["rh"], d["z"])], -1).astype(np.float64)
    c2 *= rng.choice([-1.0, 1.0], (inp.shape[0], 1)) / np.linalg.norm(c2, axis=1, keepdims=True)
    roll, yaw = np.arcsin(np.clip(c2[:, 2], -1.0, 1.0)), np.arctan2(-c2[:, 0], c2[:, 1])
    return np.stack([roll, rng.uniform(-np.pi, np.pi, inp.shape[0]), yaw], -1).astype(np.float32)


def invalid_inputs(sc: FlightScenario, rng, n):
    """Special values in each float field in turn, UTC out of range, extreme binary angles."""
    A, w = uniform_errors(rng, n)
    inp = sc.inputs(sc.geometry(rng, n), A, w)
    for r in range(n):
        case = r % 16
        if case < 12:       # one float field component
            f, i = FLOAT_FIELDS[case // 3], case % 3
            inp[f][r, i] = SPECIAL_F32[rng.integers(0, SPECIAL_F32.size)]
        elif case < 14:     # UTC out of range
            key = "utc_day" if case == 12 else "utc_ms"
            inp[key][r] = INT_SPECIAL[rng.integers(0, INT_SPECIAL.size)]
        elif case == 14:    # lon/lat extremes (every int32 is a valid binary angle)
            inp["lon"][r], inp["lat"][r] = rng.choice([-2**31, 2**31 - 1, 2**30, -2**30], 2)
        else:               # everything special at once
            for f in FLOAT_FIELDS:
                inp[f][r] = SPECIAL_F32[rng.integers(0, SPECIAL_F32.size, 3)]
    return inp


def bit_inputs(rng, n):
    """Every field a random bit pattern."""
    raw = rng.integers(0, 2**32, (n, INPUT_DTYPE.itemsize // 4), dtype=np.uint64).astype(np.uint32)
    return raw.view(INPUT_DTYPE).reshape(n).copy()


def gate_classes(sc: FlightScenario, n: int, seed: int, dwell: int, integral_limit: float | None = None,
                 config: cs.ControllerConfig | None = None) -> dict[str, Batch]:
    """n independent steps (deterministic in seed), in class order. With `integral_limit`, a share
    of the states hold an integrator just inside its limit, so that a step's error pushes it over
    (the anti-windup clamp runs); with `config`, an eighth of the bound class flies a 90° roll
    error (parallel_axis_attitudes)."""
    rng = np.random.default_rng(seed)
    counts = {k: int(n * SHARES.get(k, 0.0)) for k in KINDS}
    counts["inside"] = n - sum(counts.values())
    makers = {"inside": lambda m: inside_inputs(sc, rng, m), "bound": lambda m: bound_inputs(sc, rng, m),
              "invalid": lambda m: invalid_inputs(sc, rng, m), "bits": lambda m: bit_inputs(rng, m)}
    inputs = {k: makers[k](counts[k]) for k in KINDS if counts[k] > 0}
    if config is not None and counts["bound"] >= 8:
        rows = inputs["bound"][counts["bound"] - counts["bound"] // 8:]
        inputs["bound"]["A_bo"][-rows.shape[0]:] = parallel_axis_attitudes(config, rows, rng)
    states = random_states(rng, n, dwell)
    if integral_limit is not None:
        near = np.flatnonzero(rng.random(n) < NEAR_LIMIT_SHARE)
        side = rng.choice([-1.0, 1.0], (near.size, 3))
        states["integral"][near] = side * (integral_limit - rng.uniform(0.0, 0.004, (near.size, 3)))
    out, start = {}, 0
    for k, inp in inputs.items():
        out[k] = Batch(states[start:start + inp.shape[0]].copy(), inp)
        start += inp.shape[0]
    return out


def sequences(sc: FlightScenario, n_seq: int, steps: int, seed: int) -> np.ndarray:
    """(n_seq, steps) inputs: consecutive 0.1 s steps of a pass, errors oscillating across the
    envelope with periods of 3-20 s, NaN bursts on the gyro."""
    rng = np.random.default_rng(seed)
    out = np.zeros((n_seq, steps), dtype=INPUT_DTYPE)
    t = np.arange(steps) * 0.1
    for s in range(n_seq):
        g = sc.sequence_geometry(rng, steps)
        period = rng.uniform(3.0, 20.0, 6)
        amp = rng.uniform(0.1, 0.8, 6)
        amp[rng.integers(0, 6)] = rng.uniform(1.05, 1.6)   # one error crosses its bound periodically
        osc = amp * np.sin(2 * np.pi * t[:, None] / period + rng.uniform(0, 2 * np.pi, 6))
        inp = sc.inputs(g, osc[:, :3] * A_BOUND_DEG * DEG, osc[:, 3:] * W_BOUND_DEG * DEG)
        burst = rng.integers(0, steps - 5)
        inp["omega_b"][burst:burst + 3, rng.integers(0, 3)] = np.nan
        out[s] = inp
    return out


def cycle_classes(sc: FlightScenario, per_class: int, seed: int, dwell: int) -> dict[str, Batch]:
    """nn_path (in-envelope inputs, network mode), pid_path (an attitude error beyond its bound),
    dwell (in-envelope while the PID still flies), invalid (a NaN or Inf gyro reading), bits."""
    rng = np.random.default_rng(seed)
    n = per_class
    nn_state, dwell_state = random_states(rng, n, dwell), random_states(rng, n, dwell)
    nn_state["mode"], nn_state["clean"] = 0, 0
    dwell_state["mode"], dwell_state["clean"] = 1, 0
    A, w = uniform_errors(rng, n, 3.0)
    A[:, rng.integers(0, 3)] = rng.choice([-1.0, 1.0], n) * rng.uniform(0.021, 0.06, n) * DEG   # outside
    invalid = inside_inputs(sc, rng, n)
    invalid["omega_b"][np.arange(n), rng.integers(0, 3, n)] = rng.choice(SPECIAL_F32[:4], n)  # NaN / Inf
    return {
        "nn_path": Batch(nn_state, inside_inputs(sc, rng, n)),
        "pid_path": Batch(random_states(rng, n, dwell), sc.inputs(sc.geometry(rng, n), A, w)),
        "dwell": Batch(dwell_state, inside_inputs(sc, rng, n)),
        "invalid": Batch(random_states(rng, n, dwell), invalid),
        "bits": Batch(random_states(rng, n, dwell), bit_inputs(rng, n)),
    }
