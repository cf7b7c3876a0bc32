"""The controller unit's interface as the flight package's ICD states it: every record field with
unit, frame and range, and the status bits. Ranges that depend on the configuration or the
artifact are computed from them (never retyped)."""
from __future__ import annotations

from codegen.unit import FieldDoc, StatusBit
from codegen.units.controller import spec as cs

BAM = "binary angle, LSB = pi * 2^-31 rad"
INVALID = "non-finite -> STATUS_INPUT_INVALID (PID on zero errors)"


def field_docs(cfg: cs.ControllerConfig) -> dict[str, list[FieldDoc]]:
    lim = f"{cfg.torque_limit:g}"
    return {
        "input": [
            FieldDoc("A_bo", "rad", "S_b w.r.t. S_o", f"any finite; {INVALID}",
                     "star sensor: 3-1-2 Euler angles [phi, theta, psi] of the body w.r.t. the orbital frame"),
            FieldDoc("omega_b", "rad/s", "S_b", "any finite; a non-finite axis counts as 0 in the PID and sets "
                     "STATUS_INPUT_INVALID", "gyro: body rate w.r.t. inertial space"),
            FieldDoc("R_s", "m", "ECI (mean equator and equinox of date, via GMST)", f"any finite; {INVALID}",
                     "GPS: satellite position"),
            FieldDoc("V_s", "m/s", "ECI", f"any finite; {INVALID}", "GPS: satellite velocity"),
            FieldDoc("lon", BAM, "WGS-84 geodetic", "any int32 (wraps: 2^31 LSB = 180 deg)",
                     "telecommand: target longitude, height 0"),
            FieldDoc("lat", BAM, "WGS-84 geodetic", f"[-{cs.LAT_BAM_MAX}, {cs.LAT_BAM_MAX}] (+-90 deg); outside: "
                     "STATUS_INPUT_INVALID", "telecommand: target latitude"),
            FieldDoc("utc_day", "day", "UTC (used as UT1)", f"[{cs.UTC_DAY_MIN}, {cs.UTC_DAY_MAX}] (1900..2200; "
                     "accuracy stated for 2000..2100); outside: STATUS_INPUT_INVALID",
                     f"days since 2000-01-01 (Julian Day Number - {cs.J2000_JDN})"),
            FieldDoc("utc_ms", "ms", "UTC", f"[0, {cs.UTC_MS_MAX}) (a leap second included); outside: "
                     "STATUS_INPUT_INVALID", "milliseconds since that day's UTC midnight"),
        ],
        "output": [
            FieldDoc("torque", "N*m", "S_b", f"always finite, |torque_i| <= {lim} (the configured limit)",
                     "commanded wheel torque; hold it for the control period"),
            FieldDoc("status", "bits", "-", "STATUS_* below", "what flew and why"),
            FieldDoc("A_bd", "rad", "S_b w.r.t. S_d", "NaN possible on invalid input (always the canonical 0x7FC00000)",
                     "diagnostics: 3-1-2 Euler attitude error w.r.t. the desired frame"),
            FieldDoc("omega_e", "rad/s", "S_b", "NaN possible on invalid input (always the canonical 0x7FC00000)",
                     "diagnostics: rate error omega_b - omega_d"),
        ],
        "state": [
            FieldDoc("integral", "deg*s", "S_b axes", f"|integral_i| <= {cfg.integral_limit:g}; non-finite or beyond: "
                     "reset to 0 with STATUS_STATE_REPAIRED", "PID integrator of A_bd (runs every step: bumpless)"),
            FieldDoc("mode", "-", "-", "0 network; any other value: PID", "which law flies"),
            FieldDoc("clean", "steps", "-", f"0..{cfg.dwell_steps} (the configured dwell)",
                     "consecutive clean steps while the PID flies; the network resumes at the dwell"),
        ],
    }


def status_bits() -> list[StatusBit]:
    return [
        StatusBit("STATUS_PID", cs.STATUS_PID, "the PID commanded this step (else the network)"),
        StatusBit("STATUS_BOUNDS_MASK", cs.STATUS_BOUNDS_MASK,
                  f"bit {cs.STATUS_BOUND_SHIFT} + i: network input i (Table 2 order, 0..{cs.N_BOUNDS - 1}) outside "
                  "the envelope or NaN (macro STATUS_BOUND(i))"),
        StatusBit("STATUS_INPUT_INVALID", cs.STATUS_INPUT_INVALID,
                  "a non-finite input field, or UTC day / ms or latitude out of range"),
        StatusBit("STATUS_SATURATED", cs.STATUS_SATURATED, "at least one torque axis clipped to the limit"),
        StatusBit("STATUS_DWELL", cs.STATUS_DWELL, "inside the envelope, the PID still flies until the dwell ends"),
        StatusBit("STATUS_STATE_REPAIRED", cs.STATUS_STATE_REPAIRED,
                  "the caller's state held a non-finite or out-of-limit integrator: reset to 0"),
    ]
