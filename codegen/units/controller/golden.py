"""Golden model of the generated controller (codegen/templates/controller.c.j2): numpy float32 and
integer operations in the C's order, vectorised across a batch of independent states.

`step(artifact, cfg, state, inp)` takes structured arrays (controller_emit.STATE_DTYPE /
INPUT_DTYPE, shape (N,)), returns the OUTPUT_DTYPE array and the new state; calling it again with
that state continues N sequences. A vec3 is a tuple of three float32 arrays; sums follow the C's
parentheses; transcendental functions are codegen.detmath (never np.sin/np.tanh); the network is
codegen.units.network.golden.network_eval, computed for every row and selected where the network flies (the
C calls it only there; the rows it computes are the same).
"""
from __future__ import annotations

import math

import numpy as np

from codegen.units.controller import spec as cs
from codegen import detmath as dm
from codegen.units.network import golden
from codegen.golden_vec3 import v_add, v_cross, v_dot, v_scale, v_sub
from codegen.artifact import Artifact
from codegen.units.controller.emit import INPUT_DTYPE, OUTPUT_DTYPE, STATE_DTYPE, TURN32_HI, TURN32_LO, envelope_bounds

F32, U32, U64 = np.float32, np.uint32, np.uint64


def _f(v) -> np.float32:
    return F32(v)


def _chk(a: np.ndarray) -> np.ndarray:
    assert a.dtype == F32, a.dtype
    return a


def unit_derivs(w, w1, w2, inv=None):
    if inv is None:
        inv = _chk(_f(1.0) / dm.sqrtf(v_dot(w, w)))
    e = v_scale(w, inv)
    s1 = v_dot(e, w1)
    e1 = v_scale(v_sub(w1, v_scale(e, s1)), inv)
    s2 = _chk(v_dot(e1, w1) + v_dot(e, w2))
    e2 = v_scale(v_sub(v_sub(w2, v_scale(e1, _f(2.0) * s1)), v_scale(e, s2)), inv)
    return e, e1, e2


# ----------------------------------------------------------------------------- stages

def sincos_turns(turns: np.ndarray):
    """sincos_turns: (sin, cos) of a Q32-turn angle via the nearest quadrant + float remainder."""
    v = turns.astype(U32) + U32(0x20000000)
    quadrant = v >> U32(30)
    hi = ((v & U32(0x3FFFFF00)).astype(np.int32) - np.int32(0x20000000)).astype(F32)
    lo = (v & U32(0xFF)).astype(np.int32).astype(F32)
    c_hi, c_lo = _f(TURN32_HI), _f(TURN32_LO)
    r = _chk(hi * c_hi + (hi * c_lo + lo * c_hi))
    s, c = dm.sinf(r), dm.cosf(r)
    odd = (quadrant & U32(1)) != 0
    s0, c0 = np.where(odd, c, s), np.where(odd, -s, c)
    neg = (quadrant & U32(2)) != 0
    return np.where(neg, -s0, s0), np.where(neg, -c0, c0)


def gmst_turns(day: np.ndarray, ms: np.ndarray) -> np.ndarray:
    """controller_gmst: GMST in Q32 turns (uint32) by integer Q64 arithmetic."""
    d = day.astype(np.int64)
    t = 2 * d - 1
    q = np.full(d.shape, cs.GMST_A, dtype=U64)
    q = q + d.astype(U64) * U64(cs.GMST_B)        # two's complement wrap, as the C cast
    q = q + (t * t).astype(U64) * U64(cs.GMST_Q)
    q = q + ms.astype(np.int64).astype(U64) * U64(cs.GMST_R)
    return (q >> U64(32)).astype(U32)


def _bam_turns(bam: np.ndarray) -> np.ndarray:
    return bam.astype(np.int32).view(U32)   # a binary angle is in Q32 turns


def target(cfg: cs.ControllerConfig, lon, lat, gmst):
    """controller_target: ECI position, velocity, acceleration of the ground target."""
    lam = sincos_turns(gmst + _bam_turns(lon))
    phi = sincos_turns(_bam_turns(lat))
    nrad = _chk(_f(cfg.earth_a) / dm.sqrtf(_f(1.0) - _f(cfg.earth_e2) * (phi[0] * phi[0])))
    ncl = nrad * phi[1]
    r = (_chk(ncl * lam[1]), _chk(ncl * lam[0]), _chk((nrad * _f(1.0 - cfg.earth_e2)) * phi[0]))
    w = _f(cfg.earth_rate)
    zero = np.zeros_like(r[0])
    v = (_chk(-w * r[1]), _chk(w * r[0]), zero)
    a = (_chk(-w * v[1]), _chk(w * v[0]), zero)
    return r, v, a


def desired(cfg: cs.ControllerConfig, R, V, t):
    r_t, v_t, a_t = t
    inv_r = _chk(_f(1.0) / dm.sqrtf(v_dot(R, R)))
    a_s = v_scale(R, -((_f(cfg.mu) * inv_r) * (inv_r * inv_r)))
    z, z1, z2 = unit_derivs(v_sub(r_t, R), v_sub(v_t, V), v_sub(a_t, a_s))
    h = v_cross(R, V)
    n = v_scale(h, _f(1.0) / dm.sqrtf(v_dot(h, h)))
    rh, rh1, rh2 = unit_derivs(R, V, a_s, inv_r)
    xo, xo1, xo2 = v_cross(n, rh), v_cross(n, rh1), v_cross(n, rh2)
    y, y1, y2 = unit_derivs(
        v_cross(z, xo),
        v_add(v_cross(z1, xo), v_cross(z, xo1)),
        v_add(v_add(v_cross(z2, xo), v_scale(v_cross(z1, xo1), _f(2.0))), v_cross(z, xo2)))
    x = v_cross(y, z)
    # x' and x'' never formed: x'.y = -(x.y'), x'.z' = y'.(z x z'), x'.y' = y'.(y x z')
    yz1 = v_cross(y, z1)
    wd = (v_dot(y1, z), v_dot(z1, x), _chk(-v_dot(x, y1)))
    wdot = (_chk(v_dot(y2, z) + v_dot(y1, z1)), _chk(v_dot(z2, x) + v_dot(y1, v_cross(z, z1))),
            _chk(-(v_dot(y1, yz1) + v_dot(x, y2))))
    return {"x": x, "y": y, "z": z, "xo": xo, "n": n, "rh": rh, "wd": wd, "wdot": wdot}


def atan2_small(y: np.ndarray, x: np.ndarray) -> np.ndarray:
    """atan2_small: q - q^3/3 for |y| <= 2^-10 x (x > 0), else sg_atan2f."""
    lim = x * _f(2.0**-10)
    fast = (x > _f(0.0)) & (y <= lim) & (y >= -lim)
    q = _chk(y / x)
    return np.where(fast, _chk(q + q * ((q * q) * _f(-1.0 / 3.0))), dm.atan2f(y, x))


def asin_small(s: np.ndarray) -> np.ndarray:
    """asin_small: s + s^3/6 for |s| <= 2^-10, else sg_asinf."""
    fast = (s <= _f(2.0**-10)) & (s >= _f(-(2.0**-10)))
    return np.where(fast, _chk(s + s * ((s * s) * _f(1.0 / 6.0))), dm.asinf(s))


def attitude(A_bo: np.ndarray, d: dict):
    sphi, cphi = dm.sinf(A_bo[:, 0]), dm.cosf(A_bo[:, 0])
    sth, cth = dm.sinf(A_bo[:, 1]), dm.cosf(A_bo[:, 1])
    spsi, cpsi = dm.sinf(A_bo[:, 2]), dm.cosf(A_bo[:, 2])
    sps, spc = sphi * spsi, sphi * cpsi
    b0 = (cth * cpsi - sth * sps, cth * spsi + sth * spc, -(sth * cphi))
    b1 = (-(cphi * spsi), cphi * cpsi, sphi)
    b2 = (sth * cpsi + cth * sps, sth * spsi - cth * spc, cth * cphi)
    xo, n, rh = d["xo"], d["n"], d["rh"]
    u = v_sub(v_sub(v_scale(xo, b1[0]), v_scale(n, b1[1])), v_scale(rh, b1[2]))
    c2 = (v_dot(xo, d["z"]), -v_dot(n, d["z"]), -v_dot(rh, d["z"]))
    s = v_dot(b1, c2)
    s = np.where(s > _f(1.0), _f(1.0), np.where(s < _f(-1.0), _f(-1.0), s))
    return np.stack([asin_small(s), atan2_small(-v_dot(b0, c2), v_dot(b2, c2)),
                     atan2_small(-v_dot(u, d["x"]), v_dot(u, d["y"]))], -1)


def _is_finite(v: np.ndarray) -> np.ndarray:
    return (v - v) == _f(0.0)


def pid(cfg: cs.ControllerConfig, integral: np.ndarray, x: np.ndarray, geometry_ok: np.ndarray):
    """controller_pid: (raw command, new integrator), both (N, 3)."""
    zero = _f(0.0)
    keep = np.where(geometry_ok, _f(1.0), zero)[:, None]
    a = np.where(_is_finite(x[:, 6:9]), x[:, 6:9] * keep, zero)
    w = np.where(_is_finite(x[:, 9:12]), x[:, 9:12] * keep, zero)
    kp, ki, kd = (np.array(v, dtype=F32) for v in (cfg.kp, cfg.ki, cfg.kd))
    lim, ilim = _f(cfg.torque_limit), _f(cfg.integral_limit)
    nxt = _chk(integral + a * _f(cfg.control_period))
    raw = _chk(-((kp * a + ki * nxt) + kd * w))
    ok = (raw >= -lim) & (raw <= lim)
    nxt = np.where(nxt > ilim, ilim, np.where(nxt < -ilim, -ilim, nxt))
    return raw, np.where(ok, nxt, integral)


def repair_integral(cfg: cs.ControllerConfig, integral: np.ndarray):
    """repair_integral: a non-finite or out-of-limit integrator restarts at 0 (and is flagged)."""
    ilim = _f(cfg.integral_limit)
    ok = (integral >= -ilim) & (integral <= ilim)
    return np.where(ok, integral, _f(0.0)), ~np.all(ok, axis=1)


def update_mode(cfg: cs.ControllerConfig, mode: np.ndarray, clean_count: np.ndarray, clean: np.ndarray):
    dwell = U32(cfg.dwell_steps)
    pid_mode = mode != U32(0)
    count = np.where(pid_mode & (clean_count < dwell), clean_count + U32(1), clean_count)
    mode_next = np.where(pid_mode & (count >= dwell), U32(0), mode)
    mode_next = np.where(clean, mode_next, U32(1)).astype(U32)
    count = np.where(clean, np.where(pid_mode, count, clean_count), U32(0)).astype(U32)
    return mode_next, count


def clip(v: np.ndarray, lim: np.float32) -> np.ndarray:
    return np.where(v > lim, lim, np.where(v < -lim, -lim, np.where(v == v, v, _f(0.0))))


# ----------------------------------------------------------------------------- the step

def init(n: int) -> np.ndarray:
    """n initial states (controller_init)."""
    return np.zeros(n, dtype=STATE_DTYPE)


def _inputs_finite(inp: np.ndarray) -> np.ndarray:
    """inputs_finite: the sum of (v - v) over the 12 floats is +0 unless one is NaN or Inf."""
    d = {f: inp[f] - inp[f] for f in ("A_bo", "omega_b", "R_s", "V_s")}
    z = np.zeros(inp.shape, dtype=F32)
    for i in range(3):
        z = _chk(z + ((d["A_bo"][:, i] + d["omega_b"][:, i]) + (d["R_s"][:, i] + d["V_s"][:, i])))
    return z == _f(0.0)


def step(a: Artifact, cfg: cs.ControllerConfig, state: np.ndarray, inp: np.ndarray):
    """One controller step for each row: (outputs OUTPUT_DTYPE (N,), new state STATE_DTYPE (N,))."""
    if state.dtype != STATE_DTYPE or inp.dtype != INPUT_DTYPE or state.shape != inp.shape or inp.ndim != 1:
        raise ValueError(f"golden controller: state and input must be (N,) {STATE_DTYPE} / {INPUT_DTYPE} "
                         f"records, got {state.dtype} {state.shape} and {inp.dtype} {inp.shape}")
    with np.errstate(all="ignore"):
        return _step(a, cfg, state, inp)


def _step(a: Artifact, cfg: cs.ControllerConfig, state: np.ndarray, inp: np.ndarray):
    day, ms = inp["utc_day"], inp["utc_ms"]
    time_ok = (ms >= 0) & (ms < cs.UTC_MS_MAX) & (day >= cs.UTC_DAY_MIN) & (day <= cs.UTC_DAY_MAX)
    geometry_ok = time_ok & (inp["lat"] >= -cs.LAT_BAM_MAX) & (inp["lat"] <= cs.LAT_BAM_MAX)
    valid = _inputs_finite(inp) & geometry_ok
    g = gmst_turns(np.where(time_ok, day, 0), np.where(time_ok, ms, 0))
    R = tuple(np.ascontiguousarray(inp["R_s"][:, i]) for i in range(3))
    V = tuple(np.ascontiguousarray(inp["V_s"][:, i]) for i in range(3))
    d = desired(cfg, R, V, target(cfg, inp["lon"], inp["lat"], g))
    out = np.zeros(inp.shape, dtype=OUTPUT_DTYPE)
    out["A_bd"] = attitude(inp["A_bo"], d)
    out["omega_e"] = inp["omega_b"] - np.stack(d["wd"], -1)
    r2d = _f(180.0 / math.pi)
    x = np.concatenate([np.stack(d["wd"], -1) * r2d, np.stack(d["wdot"], -1) * r2d,
                        out["A_bd"] * r2d, out["omega_e"] * r2d], axis=1)
    assert x.dtype == F32
    env_min, env_max = envelope_bounds(a, cfg)
    inside = (x >= env_min) & (x <= env_max)
    status = np.zeros(inp.shape, dtype=U32)
    for i in range(x.shape[1]):
        status |= np.where(inside[:, i], U32(0), U32(1 << (cs.STATUS_BOUND_SHIFT + i)))
    status |= np.where(valid, U32(0), U32(cs.STATUS_INPUT_INVALID))
    status |= np.where(state["fault"] != 0, U32(cs.STATUS_INTEGRITY), U32(0))   # tables corrupted: PID only
    integral, repaired = repair_integral(cfg, state["integral"])
    raw, integral = pid(cfg, integral, x, geometry_ok)
    mode, count = update_mode(cfg, state["mode"], state["clean"], status == 0)
    nn = mode == U32(0)
    y = golden.network_eval(a, np.ascontiguousarray(x))
    cmd = np.where(nn[:, None], y, raw)
    status |= np.where(nn, U32(0), U32(cs.STATUS_PID) | np.where(status == 0, U32(cs.STATUS_DWELL), U32(0)))
    lim = _f(cfg.torque_limit)
    sat = np.any(~((cmd >= -lim) & (cmd <= lim)), axis=1)
    status |= np.where(sat, U32(cs.STATUS_SATURATED), U32(0))
    out["torque"] = clip(cmd, lim)
    out["status"] = status | np.where(repaired, U32(cs.STATUS_STATE_REPAIRED), U32(0))
    # canonical NaN diagnostics (the C canonicalises where it computes them; downstream, a NaN only
    # fails comparisons and is zeroed by the PID, so its bits matter nowhere else)
    out["A_bd"], out["omega_e"] = dm.canonf(out["A_bd"]), dm.canonf(out["omega_e"])
    new = np.zeros(inp.shape, dtype=STATE_DTYPE)
    new["integral"], new["mode"], new["clean"], new["fault"] = integral, mode, count, state["fault"]
    return out, new

