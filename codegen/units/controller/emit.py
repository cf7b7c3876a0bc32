"""C emitter of the whole flight controller (paper 001 Fig. 2): `<name>.h`, `<name>.c`, plus the
network path `<name>_nn.{h,c}` from the network unit's own templates (the MLP code is not forked) and
the deterministic math library.

Record layouts for the harnesses (numpy structured dtypes matching the C structs: all fields are
4-byte, so there is no padding) and the rendering context live here too.
"""
from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from codegen import GENERATOR_VERSION
from codegen.units.controller import spec as cs
from codegen.artifact import Artifact
from codegen.cgen import c_float, check_name, comment, unit_sources
from codegen.units.network.emit import network_sources

TEMPLATES = Path(__file__).with_name("templates")
DEFAULT_NAME = "controller"

INPUT_DTYPE = np.dtype([("A_bo", "<f4", 3), ("omega_b", "<f4", 3), ("R_s", "<f4", 3), ("V_s", "<f4", 3),
                        ("lon", "<i4"), ("lat", "<i4"), ("utc_day", "<i4"), ("utc_ms", "<i4")])
OUTPUT_DTYPE = np.dtype([("torque", "<f4", 3), ("status", "<u4"), ("A_bd", "<f4", 3), ("omega_e", "<f4", 3)])
STATE_DTYPE = np.dtype([("integral", "<f4", 3), ("mode", "<u4"), ("clean", "<u4"), ("fault", "<u4")])
# The state_in_record adapter: { state; input } -> { output; state }.
RECORD_IN_DTYPE = np.dtype([("state", STATE_DTYPE), ("input", INPUT_DTYPE)])
RECORD_OUT_DTYPE = np.dtype([("output", OUTPUT_DTYPE), ("state", STATE_DTYPE)])


# 2 pi / 2^32 rad (one Q32 turn step) as float32 hi + lo.
TURN32_HI = float(np.float32(2.0 * math.pi / 2**32))
TURN32_LO = float(np.float32(2.0 * math.pi / 2**32 - TURN32_HI))


def to_bam(angle_rad) -> np.ndarray:
    """Radians -> int32 binary angle (LSB pi 2^-31 rad), rounded, wrapped to [-pi, pi)."""
    units = np.round(np.asarray(angle_rad, dtype=np.float64) * (2.0**31 / math.pi)).astype(np.int64)
    return ((units + 2**31) % 2**32 - 2**31).astype(np.int32)


def net_name(name: str) -> str:
    return f"{name}_nn"


def _c_u64(v: int) -> str:
    return f"0x{v:016x}"


def envelope_bounds(a: Artifact, cfg: cs.ControllerConfig) -> tuple[np.ndarray, np.ndarray]:
    """(min, max) float32 as emitted; pid_only: min = FLT_MAX > max = -FLT_MAX, nothing is inside."""
    if cfg.pid_only:
        big = np.full(a.n_in, np.finfo(np.float32).max, dtype=np.float32)
        return big, -big
    return a.envelope.min, a.envelope.max


# asin(2^-10) in degrees, rounded down: every A_bd that misses the attitude's short paths is at
# least this large (or NaN). An envelope of A_bd inside it means the network never flies then.
WIDE_ANGLE_DEG = 0.0559


def wide_angles_fly(env_min: np.ndarray, env_max: np.ndarray) -> bool:
    """Whether an A_bd off the attitude's short paths can still be inside the envelope (x[6..8])."""
    lo, hi = np.asarray(env_min[6:9], dtype=np.float64), np.asarray(env_max[6:9], dtype=np.float64)
    return not bool(np.all(lo > -WIDE_ANGLE_DEG) and np.all(hi < WIDE_ANGLE_DEG))


def _key(bits: int) -> int:
    """A float32 bit pattern as an unsigned key whose order (as int32) is the floats' order:
    negative floats get their magnitude bits flipped (-0 just below +0, NaNs beyond +-Inf)."""
    return (bits ^ (0x7FFFFFFF if bits >> 31 else 0)) & 0xFFFFFFFF


def envelope_checks(env_min: np.ndarray, env_max: np.ndarray) -> list[dict]:
    """Per network input, the integer test on its float32 bit pattern b that is true exactly when
    !(x >= min && x <= max), NaN included (tests/codegen/units/controller checks every case):
    'sym': min = -max > 0: (b << 1) > (bits(max) << 1); 'range': (key(b) - key_lo) > (key_hi - key_lo)
    (unsigned) with key_lo the key of -0 when min is a zero, key_hi that of +0 when max is a zero;
    'empty': min > max, always outside."""
    out = []
    for lo, hi in zip(np.asarray(env_min, dtype=np.float32), np.asarray(env_max, dtype=np.float32)):
        blo, bhi = int(lo.view(np.uint32)), int(hi.view(np.uint32))
        if not (np.isfinite(lo) and np.isfinite(hi)):
            raise ValueError(f"envelope bounds must be finite, got [{lo}, {hi}]")
        if lo > hi:
            out.append({"kind": "empty"})
        elif lo == -hi and hi > 0:
            out.append({"kind": "sym", "limit": f"0x{(bhi << 1) & 0xFFFFFFFF:08x}u"})
        else:
            klo = _key(0x80000000) if lo == 0 else _key(blo)
            khi = _key(0) if hi == 0 else _key(bhi)
            out.append({"kind": "range", "key_lo": f"0x{klo:08x}u", "span": f"0x{(khi - klo) & 0xFFFFFFFF:08x}u"})
    return out


def envelope_outside(checks: list[dict], bits: np.ndarray) -> np.ndarray:
    """numpy mirror of the emitted tests: (N, n_in) uint32 bit patterns -> (N, n_in) bool outside."""
    b = np.asarray(bits, dtype=np.uint32).astype(np.uint64)
    out = np.zeros(b.shape, dtype=bool)
    m = np.uint64(0xFFFFFFFF)
    key = b ^ np.where((b >> np.uint64(31)) != 0, np.uint64(0x7FFFFFFF), np.uint64(0))
    for i, c in enumerate(checks):
        if c["kind"] == "empty":
            out[:, i] = True
        elif c["kind"] == "sym":
            out[:, i] = ((b[:, i] << np.uint64(1)) & m) > np.uint64(int(c["limit"][:-1], 16))
        else:
            d = (key[:, i] + np.uint64(2**32) - np.uint64(int(c["key_lo"][:-1], 16))) & m
            out[:, i] = d > np.uint64(int(c["span"][:-1], 16))
    return out


def gmst_horner() -> dict:
    """The GMST constants of the C's Horner form (A + Q) + d ((B - 4Q) + 4Q d) mod 2^64, equal to
    A + B d + Q (2d - 1)^2 for every day; 4Q d must fit an int32 over the accepted days."""
    q4 = 4 * cs.GMST_Q
    if q4 * max(abs(cs.UTC_DAY_MIN), abs(cs.UTC_DAY_MAX)) >= 2**31:
        raise ValueError("GMST: 4 Q d overflows int32 over the accepted days")
    return {"gmst_a2": _c_u64((cs.GMST_A + cs.GMST_Q) % 2**64), "gmst_b2": _c_u64((cs.GMST_B - q4) % 2**64),
            "gmst_q4": str(q4)}


def controller_context(a: Artifact, cfg: cs.ControllerConfig, name: str) -> dict:
    f = c_float
    env_min, env_max = envelope_bounds(a, cfg)
    wide_fly = wide_angles_fly(env_min, env_max)
    return {
        "name": name, "P": name.upper(), "net": net_name(name), "NET": net_name(name).upper(), "n_in": a.n_in,
        "generator_version": GENERATOR_VERSION, "sha256": a.sha256,
        "creator": comment(a.metadata.get("creator", "")),
        "status_pid": cs.STATUS_PID, "status_bounds_mask": cs.STATUS_BOUNDS_MASK,
        "status_invalid": cs.STATUS_INPUT_INVALID, "status_saturated": cs.STATUS_SATURATED,
        "status_dwell": cs.STATUS_DWELL, "status_integrity": cs.STATUS_INTEGRITY, "lat_bam_max": cs.LAT_BAM_MAX, "status_state_repaired": cs.STATUS_STATE_REPAIRED,
        "status_bound_shift": cs.STATUS_BOUND_SHIFT,
        "utc_ms_max": cs.UTC_MS_MAX, "utc_day_min": cs.UTC_DAY_MIN, "utc_day_max": cs.UTC_DAY_MAX,
        "gmst_a": _c_u64(cs.GMST_A), "gmst_b": _c_u64(cs.GMST_B), "gmst_q": _c_u64(cs.GMST_Q),
        "gmst_r": _c_u64(cs.GMST_R), **gmst_horner(),
        "turn32_hi": f(TURN32_HI), "turn32_lo": f(TURN32_LO), "earth_a": f(cfg.earth_a), "earth_e2": f(cfg.earth_e2),
        "one_minus_e2": f(1.0 - cfg.earth_e2), "earth_rate": f(cfg.earth_rate), "mu": f(cfg.mu),
        "rad2deg": f(180.0 / math.pi), "minus_third": f(-1.0 / 3.0), "sixth": f(1.0 / 6.0), "torque_limit": f(cfg.torque_limit),
        "torque_limit_text": f"{cfg.torque_limit:g}",
        "torque_limit_bits": f"0x{int(np.float32(cfg.torque_limit).view(np.uint32)):08x}",
        "integral_limit_bits": f"0x{int(np.float32(cfg.integral_limit).view(np.uint32)):08x}",
        "integral_limit_bits2": f"0x{(int(np.float32(cfg.integral_limit).view(np.uint32)) << 1) & 0xFFFFFFFF:08x}",
        "torque_limit_bits2": f"0x{(int(np.float32(cfg.torque_limit).view(np.uint32)) << 1) & 0xFFFFFFFF:08x}",
        "control_period": f(cfg.control_period), "integral_limit": f(cfg.integral_limit),
        "dwell_steps": int(cfg.dwell_steps),
        "kp": [f(v) for v in cfg.kp], "ki": [f(v) for v in cfg.ki], "kd": [f(v) for v in cfg.kd],
        "env_min": [f(v) for v in env_min], "env_max": [f(v) for v in env_max],
        "wide_may_fly": int(wide_fly), "env_checks": envelope_checks(env_min, env_max),
        "wide_note": ("an A_bd envelope wider than asin(2^-10): the network may still fly" if wide_fly else
                      "the A_bd envelope lies inside +-asin(2^-10): a bound bit is set, the PID flies"),
    }


def controller_sources(a: Artifact, cfg: cs.ControllerConfig, name: str = DEFAULT_NAME) -> dict[str, str]:
    """{file name: text}: the controller, its network path and sg_math."""
    check_name(name)
    if a.sizes[0] != 12 or a.sizes[2] != 3:
        raise ValueError(f"the controller needs a 12-input, 3-output network, got {a.shape_text}")
    sources = network_sources(a, net_name(name))
    sources.update(unit_sources(TEMPLATES, "controller", name, controller_context(a, cfg, name), with_math=False))
    return sources
