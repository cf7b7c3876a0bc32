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
from codegen.cgen import c_float, check_name, comment, environment
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


def controller_context(a: Artifact, cfg: cs.ControllerConfig, name: str) -> dict:
    f = c_float
    env_min, env_max = envelope_bounds(a, cfg)
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
        "gmst_r": _c_u64(cs.GMST_R),
        "turn32_hi": f(TURN32_HI), "turn32_lo": f(TURN32_LO), "earth_a": f(cfg.earth_a), "earth_e2": f(cfg.earth_e2),
        "one_minus_e2": f(1.0 - cfg.earth_e2), "earth_rate": f(cfg.earth_rate), "mu": f(cfg.mu),
        "rad2deg": f(180.0 / math.pi), "minus_third": f(-1.0 / 3.0), "sixth": f(1.0 / 6.0), "torque_limit": f(cfg.torque_limit),
        "torque_limit_text": f"{cfg.torque_limit:g}",
        "control_period": f(cfg.control_period), "integral_limit": f(cfg.integral_limit),
        "dwell_steps": int(cfg.dwell_steps),
        "kp": [f(v) for v in cfg.kp], "ki": [f(v) for v in cfg.ki], "kd": [f(v) for v in cfg.kd],
        "env_min": [f(v) for v in env_min], "env_max": [f(v) for v in env_max],
    }


def controller_sources(a: Artifact, cfg: cs.ControllerConfig, name: str = DEFAULT_NAME) -> dict[str, str]:
    """{file name: text}: the controller, its network path and sg_math."""
    check_name(name)
    if a.sizes[0] != 12 or a.sizes[2] != 3:
        raise ValueError(f"the controller needs a 12-input, 3-output network, got {a.shape_text}")
    env, ctx = environment(TEMPLATES), controller_context(a, cfg, name)
    sources = network_sources(a, net_name(name))
    sources[f"{name}.h"] = env.get_template("controller.h.j2").render(ctx)
    sources[f"{name}.c"] = env.get_template("controller.c.j2").render(ctx)
    return sources
