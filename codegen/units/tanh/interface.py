"""The tanh-law unit's interface as the flight package's ICD states it (fields and status values);
the torque and varpi bounds are computed from the parameters, the status values are the golden
model's constants (the C's are emitted from the same numbers).

The status macros are named here without the C entry prefix (`STATUS_SINGULAR` is
`<NAME>_STATUS_SINGULAR` in C); the ICD adds the prefix."""
from __future__ import annotations

from codegen.unit import FieldDoc, StatusBit
from codegen.units.tanh.golden import STATUS_INVALID_INPUT, STATUS_OK, STATUS_SINGULAR
from codegen.units.tanh.params import TanhParams

DCM = "row-major 3x3, R[3*i + j] = R_ij, maps its body frame to the reference frame"
INVALID = ("non-finite (or so large that R_e or w_e overflow) -> zero torque, x1 = x2 = 0, varpi held, "
           "STATUS_INVALID_INPUT")


def _num(x: float) -> str:
    return f"{float(x):.9g}"


def field_docs(p: TanhParams) -> dict[str, list[FieldDoc]]:
    bound, vlim = _num(p.k1 + p.k2 + p.k3), _num(p.varpi_limit)
    matrix = (f"entries in [-1, 1] for a rotation matrix; any finite matrix is used as given (not re-orthonormalised; "
              f"E^-1 assumes a unit error quaternion, so far from SO(3) torque and varpi depart, finitely, from the "
              f"float64 law); {INVALID}")
    return {
        "input": [
            FieldDoc("R_c", "-", "body -> reference", matrix, f"body attitude ({DCM})"),
            FieldDoc("w_c", "rad/s", "body", f"any finite; {INVALID}", "body rate"),
            FieldDoc("R_t", "-", "target -> reference", matrix, f"target attitude ({DCM})"),
            FieldDoc("w_t", "rad/s", "target", f"any finite; {INVALID}", "target rate"),
            FieldDoc("wdot_t", "rad/s^2", "target", f"any finite; {INVALID}", "target angular acceleration"),
        ],
        "output": [
            FieldDoc("torque", "N*m", "body", f"always finite, |torque_i| <= k1 + k2 + k3 = {bound}",
                     "control torque u of eq. 17; hold it for the control period"),
            FieldDoc("x1", "-", "body", "always finite, |x1| = sin(angle/2) <= 1 for rotation matrices; 0 on "
                     "STATUS_INVALID_INPUT", "attitude error e (vector part of the error quaternion; near 180 deg "
                     "the fallback's error)"),
            FieldDoc("x2", "rad/s", "body", "always finite; 0 unless the nominal law ran (status 0)",
                     "w_e - w_ev (eq. 9)"),
            FieldDoc("varpi", "rad/s", "body", f"always finite, |varpi_i| <= varpi_limit = {vlim}",
                     "auxiliary state after this step (equals the new state)"),
            FieldDoc("status", "value", "-",
                     f"exactly one of {STATUS_OK} (nominal law), STATUS_SINGULAR, STATUS_INVALID_INPUT",
                     "which branch ran"),
        ],
        "state": [
            FieldDoc("varpi", "rad/s", "body", f"|varpi_i| <= {vlim} after every step; non-finite from the "
                     "caller: reset to 0 (STATUS_INVALID_INPUT)", "auxiliary system state of eq. 18 (init: 0)"),
        ],
    }


def status_bits() -> list[StatusBit]:
    return [
        StatusBit("STATUS_SINGULAR", STATUS_SINGULAR,
                  "near 180 deg (q0 below q0_min): bounded saturated PD, varpi held; caller: telemetry"),
        StatusBit("STATUS_INVALID_INPUT", STATUS_INVALID_INPUT,
                  "non-finite input, state or result: zero torque, varpi held; caller: FDIR on the attitude "
                  "source if it persists"),
    ]
