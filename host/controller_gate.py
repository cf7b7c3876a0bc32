"""Input vectors and the three-way bit-exact gate of the whole controller step (golden == x86 == ARM).

Vectors are realistic where it matters: the Table 5 pass over the central target and the 100
staring targets, moved to a random UTC in 2000-2100 (R_s, V_s rotated about z by the GMST
difference, so the Earth-fixed geometry is the same), with the attitude and rate errors chosen
in S_d and converted to the star-sensor A_bo and gyro ω_b in float64. Classes:
  inside    errors uniform inside Table 2, random controller states (either mode, any dwell count);
  bound     one of A_bd / ω_e at a bound ×(1 ± 1e-3), or a target far off-track (ω_d bounds);
  invalid   one field (or all) of the input set to NaN, ±Inf, ±FLT_MAX, ±0, subnormals; UTC
            day or ms out of range;
  bits      every field a random bit pattern.
Sequences: S runs of T consecutive 0.1 s steps from init, errors oscillating across the envelope
(mode switches and dwells), with bursts of NaN inputs.
"""
from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from codegen import bitcompare
from codegen import controller_spec as cs
from codegen import golden_controller as gc
from codegen.artifact import Artifact
from codegen.controller_emit import INPUT_DTYPE, OUTPUT_DTYPE, to_bam
from host.constants import DEG
from host.frames import L_oi
from host.guidance import desired_state
from host.orbit import TABLE5_EPOCH, propagate_rk4, table5_initial_state
from host.rotations import dcm_from_euler312, euler312_from_dcm, frame_rot_z
from host.targets import central_target, staring_targets
from host.timebase import gmst

KINDS = ("inside", "bound", "invalid", "bits")
SHARES = {"bound": 0.2, "invalid": 0.15, "bits": 0.05}   # inside takes the rest
PASS_SECONDS = 300.0
DAYS_2000_2100 = 36525


@dataclass
class Geometry:
    jd: np.ndarray
    sec: np.ndarray
    R: np.ndarray
    V: np.ndarray
    lon: np.ndarray
    lat: np.ndarray


def _pass_states(step: float = 0.1) -> np.ndarray:
    n = int(PASS_SECONDS / step)
    return propagate_rk4(table5_initial_state(), step, n)


_PASS = None


def pass_states() -> np.ndarray:
    global _PASS
    if _PASS is None:
        _PASS = _pass_states()
    return _PASS


def random_geometry(rng: np.random.Generator, n: int, far_targets: bool = False) -> Geometry:
    """n samples of the pass at random instants, staring at the paper's targets (or far off-track
    ones), moved to random UTC instants in 2000-2100."""
    states = pass_states()
    k = rng.integers(0, states.shape[0], n)
    t = k * 0.1
    tgs = [central_target(), *staring_targets()]
    pick = rng.integers(0, len(tgs), n)
    lon = np.array([tgs[i].lon for i in pick])
    lat = np.array([tgs[i].lat for i in pick])
    if far_targets:   # up to ~600 km off the central target: ω_d leaves Table 2 near closest approach
        lon = lon + rng.uniform(-6, 6, n) * DEG
        lat = lat + rng.uniform(-3, 3, n) * DEG
    jd0, sec0 = TABLE5_EPOCH
    day = rng.integers(0, DAYS_2000_2100, n)
    ms = rng.integers(0, 86_400_000, n)
    jd, sec = cs.J2000_JDN + day, ms / 1000.0
    delta = gmst(jd, sec) - gmst(jd0, sec0 + t)
    rot = frame_rot_z(-delta)
    R = np.einsum("nij,nj->ni", rot, states[k, :3])
    V = np.einsum("nij,nj->ni", rot, states[k, 3:])
    return Geometry(jd, sec, R, V, lon, lat)


def make_inputs(g: Geometry, A_bd: np.ndarray, omega_e: np.ndarray) -> np.ndarray:
    """Sensor readings that give these errors: L_bo = L_bd L_di L_oi^T, ω_b = ω_e + ω_d (float64)."""
    d = desired_state(g.jd, g.sec, g.R, g.V, g.lon, g.lat)
    L_bo = dcm_from_euler312(A_bd) @ d.L_di @ np.swapaxes(L_oi(g.R, g.V), -1, -2)
    inp = np.zeros(g.jd.shape, dtype=INPUT_DTYPE)
    inp["A_bo"], inp["omega_b"] = euler312_from_dcm(L_bo), omega_e + d.omega_d
    inp["R_s"], inp["V_s"] = g.R, g.V
    inp["lon"], inp["lat"] = to_bam(g.lon), to_bam(g.lat)
    inp["utc_day"] = g.jd - cs.J2000_JDN
    inp["utc_ms"] = np.round(g.sec * 1000.0).astype(np.int64)
    return inp


CORRUPT_INTEGRALS = np.array([np.nan, np.inf, -np.inf, 3.4028235e38, -1e6, 1e6], dtype=np.float32)
CORRUPT_SHARE = 0.02


def random_states(rng: np.random.Generator, n: int, dwell: int) -> np.ndarray:
    """Reachable states, plus a few corrupted integrators (bit flips) that the step must repair."""
    st = gc.init(n)
    st["integral"] = rng.uniform(-1.0, 1.0, (n, 3))
    st["mode"] = rng.integers(0, 2, n)
    st["clean"] = rng.integers(0, dwell + 1, n)
    bad = np.flatnonzero(rng.random(n) < CORRUPT_SHARE)
    st["integral"][bad, rng.integers(0, 3, bad.size)] = rng.choice(CORRUPT_INTEGRALS, bad.size)
    return st


def uniform_errors(rng, n, scale=1.0):
    """(A_bd [rad], ω_e [rad/s]) uniform in scale × the Table 2 error bounds, (n, 3) each."""
    return (rng.uniform(-0.02, 0.02, (n, 3)) * scale * DEG, rng.uniform(-0.004, 0.004, (n, 3)) * scale * DEG)


def bound_inputs(rng, n):
    """Half: one attitude or rate error at a bound ×(1 ± 1e-3); half: targets far off-track."""
    A, w = uniform_errors(rng, n, 0.9)
    half = n // 2
    rows = np.arange(half)
    col = rng.integers(0, 6, half)
    side = rng.choice([-1.0, 1.0], half)
    factor = 1.0 + rng.choice([-1e-3, 1e-3], half)
    A[rows[col < 3], col[col < 3]] = (side * factor * 0.02 * DEG)[col < 3]
    w[rows[col >= 3], col[col >= 3] - 3] = (side * factor * 0.004 * DEG)[col >= 3]
    g_near = random_geometry(rng, half)
    g_far = random_geometry(rng, n - half, far_targets=True)
    return np.concatenate([make_inputs(g_near, A[:half], w[:half]), make_inputs(g_far, A[half:], w[half:])])


SPECIAL_F32 = np.array([np.nan, -np.nan, np.inf, -np.inf, np.finfo(np.float32).max, -np.finfo(np.float32).max,
                        0.0, -0.0, 1e-45, -1e-45, 1.1754942e-38], dtype=np.float32)
FLOAT_FIELDS = ("A_bo", "omega_b", "R_s", "V_s")
INT_SPECIAL = np.array([-2**31, -1, 0, 2**31 - 1, cs.UTC_MS_MAX, cs.UTC_DAY_MAX + 1, cs.UTC_DAY_MIN - 1],
                       dtype=np.int64)


def invalid_inputs(rng, n):
    """Special values in each float field in turn, UTC out of range, extreme binary angles."""
    A, w = uniform_errors(rng, n)
    inp = make_inputs(random_geometry(rng, n), A, w)
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


def gate_inputs(n: int, seed: int, dwell: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(states, inputs, kind index) for n independent steps, in class order."""
    rng = np.random.default_rng(seed)
    counts = {k: int(n * SHARES.get(k, 0.0)) for k in KINDS}
    counts["inside"] = n - sum(counts.values())
    makers = {"inside": lambda m: make_inputs(random_geometry(rng, m), *uniform_errors(rng, m, 0.95)),
              "bound": lambda m: bound_inputs(rng, m), "invalid": lambda m: invalid_inputs(rng, m),
              "bits": lambda m: bit_inputs(rng, m)}
    inputs = np.concatenate([makers[k](counts[k]) for k in KINDS if counts[k] > 0])
    kind = np.repeat(np.arange(len(KINDS), dtype=np.uint8), [counts[k] for k in KINDS])
    return random_states(rng, n, dwell), inputs, kind


def sequence_inputs(n_seq: int, steps: int, seed: int) -> np.ndarray:
    """(n_seq, steps) inputs: consecutive 0.1 s steps of the pass (looping over it), errors
    oscillating across the envelope with periods of 3-20 s, NaN bursts on the gyro."""
    rng = np.random.default_rng(seed)
    states = pass_states()
    out = np.zeros((n_seq, steps), dtype=INPUT_DTYPE)
    tgs = [central_target(), *staring_targets()]
    t = np.arange(steps) * 0.1
    for s in range(n_seq):
        k = (rng.integers(0, states.shape[0]) + np.arange(steps)) % states.shape[0]
        tg = tgs[rng.integers(0, len(tgs))]
        day, ms0 = rng.integers(0, DAYS_2000_2100), rng.integers(0, 86_400_000 - 100 * steps)
        jd, sec = np.full(steps, cs.J2000_JDN + day), (ms0 + 100 * np.arange(steps)) / 1000.0
        delta = gmst(jd, sec) - gmst(TABLE5_EPOCH[0], TABLE5_EPOCH[1] + k * 0.1)
        rot = frame_rot_z(-delta)
        g = Geometry(jd, sec, np.einsum("nij,nj->ni", rot, states[k, :3]),
                     np.einsum("nij,nj->ni", rot, states[k, 3:]), np.full(steps, tg.lon), np.full(steps, tg.lat))
        period = rng.uniform(3.0, 20.0, 6)
        amp = rng.uniform(0.1, 0.8, 6)
        amp[rng.integers(0, 6)] = rng.uniform(1.05, 1.6)   # one error crosses its bound periodically
        osc = amp * np.sin(2 * np.pi * t[:, None] / period + rng.uniform(0, 2 * np.pi, 6))
        inp = make_inputs(g, osc[:, :3] * 0.02 * DEG, osc[:, 3:] * 0.004 * DEG)
        burst = rng.integers(0, steps - 5)
        inp["omega_b"][burst:burst + 3, rng.integers(0, 3)] = np.nan
        out[s] = inp
    return out


# ----------------------------------------------------------------------------- comparison

def compare_outputs(expected: np.ndarray, actual: np.ndarray) -> list[str]:
    """Bit comparison of every field (floats as uint32 with NaN as a class); [] when identical."""
    problems = []
    for f in OUTPUT_DTYPE.names:
        e, a = np.ascontiguousarray(expected[f]), np.ascontiguousarray(actual[f])
        if e.dtype == np.float32:
            c = bitcompare.compare(e.reshape(e.shape[0], -1), a.reshape(a.shape[0], -1))
            if not c.ok:
                problems.append(f"{f}: " + "; ".join(c.report()))
        elif not np.array_equal(e, a):
            problems.append(f"{f}: {int(np.sum(e != a))} differences")
    return problems


def compare_states(expected: np.ndarray, actual: np.ndarray) -> list[str]:
    problems = []
    c = bitcompare.compare(np.ascontiguousarray(expected["integral"]), np.ascontiguousarray(actual["integral"]))
    if not c.ok:
        problems.append("state.integral: " + "; ".join(c.report()))
    for f in ("mode", "clean"):
        if not np.array_equal(expected[f], actual[f]):
            problems.append(f"state.{f}: {int(np.sum(expected[f] != actual[f]))} differences")
    return problems


def torque_problems(out: np.ndarray, limit: float) -> list[str]:
    """Torque finite and within the wheel limit on every row."""
    tq = out["torque"]
    bad = ~np.isfinite(tq) | (np.abs(tq) > np.float32(limit))
    return [f"torque non-finite or over the limit in {int(bad.any(axis=-1).sum())} rows"] if bad.any() else []


class ArmRunner:
    """The two ARM builds (state in the records; state in the adapter) on one artifact."""

    def __init__(self, a: Artifact, cfg: cs.ControllerConfig):
        from host.sil import controller_arm_build
        from tools.m4.harness import Harness

        self.records = Harness(controller_arm_build(a, cfg, "state_in_record").elf)
        self.seq = Harness(controller_arm_build(a, cfg, "stateful").elf)

    def run_records(self, states, inputs):
        from codegen.controller_emit import RECORD_IN_DTYPE, RECORD_OUT_DTYPE

        rec = np.zeros(inputs.shape, dtype=RECORD_IN_DTYPE)
        rec["state"], rec["input"] = states, inputs
        raw = self.records.run(rec.view(np.uint8).reshape(rec.size, -1))
        out = raw.view(RECORD_OUT_DTYPE).reshape(rec.size)
        return out["output"].copy(), out["state"].copy()

    def run_sequence(self, inputs):
        self.seq.reset()
        raw = self.seq.run(np.ascontiguousarray(inputs).view(np.uint8).reshape(inputs.size, -1))
        return raw.view(OUTPUT_DTYPE).reshape(inputs.size).copy()


def run_gate(a: Artifact, cfg: cs.ControllerConfig, n: int, n_seq: int, steps: int, seed: int = 0,
             targets=("x86", "arm"), log=print) -> bool:
    """Golden vs each target on n independent steps and n_seq sequences of `steps` steps."""
    from firmware.x86_controller import X86Controller

    t0 = time.perf_counter()
    states, inputs, kind = gate_inputs(n, seed, cfg.dwell_steps)
    seqs = sequence_inputs(n_seq, steps, seed + 1)
    log(f"vectors: {n} steps (" + ", ".join(f"{k} {int(np.sum(kind == i))}" for i, k in enumerate(KINDS))
        + f"), {n_seq} sequences x {steps} steps; built in {time.perf_counter() - t0:.1f} s")
    t0 = time.perf_counter()
    g_out, g_state = gc.step(a, cfg, states, inputs)
    g_seq = gc.run_sequences(a, cfg, seqs)
    log(f"golden: {time.perf_counter() - t0:.1f} s; modes in sequences: PID on "
        f"{100.0 * np.mean(g_seq['status'] & cs.STATUS_PID != 0):.0f} % of steps, "
        f"{int(np.sum(np.diff((g_seq['status'] & cs.STATUS_PID) != 0, axis=1)))} mode switches")
    ok = not _report("golden", torque_problems(g_out, cfg.torque_limit) + torque_problems(g_seq, cfg.torque_limit), log)
    for target in targets:
        t0 = time.perf_counter()
        runner = X86Controller(a, cfg) if target == "x86" else ArmRunner(a, cfg)
        out, st = runner.run_records(states, inputs)
        problems = compare_outputs(g_out, out) + compare_states(g_state, st)
        for s in range(n_seq):
            if target == "x86":
                runner.reset()
            got = runner.run_sequence(seqs[s])
            problems += [f"sequence {s}: {p}" for p in compare_outputs(g_seq[s], got)]
        ok &= not _report(f"{target} vs golden ({time.perf_counter() - t0:.1f} s)", problems, log)
    return ok


def _report(what: str, problems: list[str], log) -> bool:
    log(f"{what}: " + ("identical" if not problems else "MISMATCH"))
    for p in problems[:10]:
        log("  " + p)
    return bool(problems)
