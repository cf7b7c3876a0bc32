"""The controller unit's interface as the flight package's ICD states it: every record field with
unit, frame and range, and the status bits. Ranges that depend on the configuration or the
artifact are computed from them (never retyped); the status masks are the spec's constants.

The status macros are named here without the C entry prefix (`STATUS_PID` is `<NAME>_STATUS_PID`
in C); the ICD adds the prefix."""
from __future__ import annotations

import numpy as np

from codegen.detmath import TRIG_MAX_ARG
from codegen.unit import FieldDoc, StatusBit
from codegen.units.controller import spec as cs

BAM = "binary angle, LSB = pi * 2^-31 rad"
INVALID = "non-finite -> STATUS_INPUT_INVALID, the PID flies with every non-finite error counted as 0"
CANON_NAN = "the canonical NaN 0x7FC00000"


def number(x: float) -> str:
    """A configured value as written (shortest repr), plus the float32 the C compares with when
    that differs from it."""
    x = float(x)
    f = np.float32(x)
    return repr(x) if float(f) == x else f"{x!r} (as float32: {float(f):.9g})"


def _deg(bam: int) -> str:
    return f"{bam * 180.0 / 2 ** 31:g} deg"


def field_docs(cfg: cs.ControllerConfig) -> dict[str, list[FieldDoc]]:
    lim, ilim, dwell = number(cfg.torque_limit), number(cfg.integral_limit), int(cfg.dwell_steps)
    period = repr(float(cfg.control_period))
    return {
        "input": [
            FieldDoc("A_bo", "rad", "S_b w.r.t. S_o",
                     f"nominally [-pi, pi]; sin/cos accurate for |A_bo_i| <= {TRIG_MAX_ARG:g} (sg_math domain), "
                     f"beyond it finite and bit-exact but less accurate; {INVALID}",
                     "star sensor: 3-1-2 Euler angles [phi, theta, psi] of the body w.r.t. the orbital frame"),
            FieldDoc("omega_b", "rad/s", "S_b",
                     "any finite; a non-finite axis sets STATUS_INPUT_INVALID and counts as a zero rate error "
                     "in the PID", "gyro: body rate w.r.t. inertial space"),
            FieldDoc("R_s", "m", "ECI (mean equator and equinox of date, via GMST)",
                     f"any finite, |R_s| > 0 (R_s = 0 or V_s parallel to R_s: NaN errors, STATUS_BOUND bits, "
                     f"the PID flies on zero errors); {INVALID}", "GPS: satellite position"),
            FieldDoc("V_s", "m/s", "ECI", f"any finite; {INVALID}", "GPS: satellite velocity"),
            FieldDoc("lon", BAM, "WGS-84 geodetic", f"any int32 (wraps: 2^31 LSB = {_deg(2 ** 31)})",
                     "telecommand: target longitude, height 0"),
            FieldDoc("lat", BAM, "WGS-84 geodetic",
                     f"[-{cs.LAT_BAM_MAX}, {cs.LAT_BAM_MAX}] (+-{_deg(cs.LAT_BAM_MAX)}); outside: "
                     "STATUS_INPUT_INVALID, the PID flies on zero errors", "telecommand: target latitude"),
            FieldDoc("utc_day", "day", "UTC (used as UT1)",
                     f"[{cs.UTC_DAY_MIN}, {cs.UTC_DAY_MAX}] (1900..2200; accuracy stated for 2000..2100); "
                     "outside: STATUS_INPUT_INVALID, the PID flies on zero errors",
                     f"days since 2000-01-01 (Julian Day Number - {cs.J2000_JDN})"),
            FieldDoc("utc_ms", "ms", "UTC",
                     f"[0, {cs.UTC_MS_MAX}) (a leap second included); outside: STATUS_INPUT_INVALID, the PID "
                     "flies on zero errors", "milliseconds since that day's UTC midnight"),
        ],
        "output": [
            FieldDoc("torque", "N*m", "S_b",
                     f"always finite, |torque_i| <= {lim} (limits.torque_limit) for every input and state; "
                     "a clipped axis sets STATUS_SATURATED",
                     f"commanded wheel torque; hold it for the control period ({period} s)"),
            FieldDoc("status", "bits", "-", "an OR of the STATUS_* bits below; 0: the network flew, all clean",
                     "what flew and why"),
            FieldDoc("A_bd", "rad", "S_b w.r.t. S_d",
                     f"phi in [-pi/2, pi/2], theta and psi in [-pi, pi]; {CANON_NAN} on a non-finite or "
                     "degenerate input", "diagnostics: 3-1-2 Euler attitude error w.r.t. the desired frame"),
            FieldDoc("omega_e", "rad/s", "S_b", f"finite for finite inputs; {CANON_NAN} on a non-finite or "
                     "degenerate input", "diagnostics: rate error omega_b - omega_d"),
        ],
        "state": [
            FieldDoc("integral", "deg*s", "S_b axes",
                     f"|integral_i| <= {ilim} (pid.integral_limit); non-finite or beyond: reset to 0 with "
                     "STATUS_STATE_REPAIRED", "PID integrator of A_bd (advances every step, whichever law flies: "
                     "bumpless; held on an axis whose PID command saturates)"),
            FieldDoc("mode", "-", "-", f"{cs.MODE_NN}: network; any other value: PID (the step writes "
                     f"{cs.MODE_NN} or {cs.MODE_PID})", "which law flies"),
            FieldDoc("clean", "steps", "-",
                     f"0..{dwell} (timing.dwell_steps); a larger value from the caller: the network resumes at "
                     "the next clean step", f"consecutive clean steps while the PID flies; the network resumes "
                     f"after {dwell} ({dwell * cfg.control_period:.6g} s)"),
            FieldDoc("fault", "-", "-", "0: tables intact; set by init / integrity_check when the network's "
                     "constant tables fail their CRC-32, then only the PID flies (STATUS_INTEGRITY) until init",
                     "integrity of the network's constant tables"),
        ],
    }


def status_bits() -> list[StatusBit]:
    return [
        StatusBit("STATUS_PID", cs.STATUS_PID,
                  "the PID commanded this step (else the network); caller: telemetry only"),
        StatusBit("STATUS_BOUNDS_MASK", cs.STATUS_BOUNDS_MASK,
                  f"bit {cs.STATUS_BOUND_SHIFT} + i (macro STATUS_BOUND(i)): network input i (Table 2 order, "
                  f"0..{cs.N_BOUNDS - 1}) outside the envelope or NaN, the PID flies; caller: telemetry, expected "
                  "during large manoeuvres"),
        StatusBit("STATUS_INPUT_INVALID", cs.STATUS_INPUT_INVALID,
                  "a non-finite input field, or UTC day / ms or latitude out of range: PID on the finite errors "
                  "(none when UTC or latitude is invalid); caller: FDIR on the sensors / telecommand if it persists"),
        StatusBit("STATUS_SATURATED", cs.STATUS_SATURATED,
                  "at least one torque axis clipped to the limit; caller: telemetry"),
        StatusBit("STATUS_DWELL", cs.STATUS_DWELL,
                  "inside the envelope, the PID still flies until the dwell ends; caller: telemetry"),
        StatusBit("STATUS_STATE_REPAIRED", cs.STATUS_STATE_REPAIRED,
                  "the caller's state held a non-finite or out-of-limit integrator, reset to 0; caller: the "
                  "state's memory was corrupted (bit flip, overwrite): FDIR event"),
        StatusBit("STATUS_INTEGRITY", cs.STATUS_INTEGRITY,
                  "the network's constant tables failed their CRC-32 (init or integrity_check): only the PID "
                  "flies until init finds them intact; caller: FDIR event, reload or re-flash the image"),
    ]

