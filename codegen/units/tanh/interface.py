"""The tanh-law unit's interface as the flight package's ICD states it (fields and status values);
the torque bound is computed from the parameters."""
from __future__ import annotations

from codegen.unit import FieldDoc, StatusBit
from codegen.units.tanh.golden import STATUS_INVALID_INPUT, STATUS_SINGULAR
from codegen.units.tanh.params import TanhParams

DCM = "row-major 3x3, R[3*i + j] = R_ij, maps its body frame to the reference frame"
INVALID = "non-finite -> zero torque, varpi held, STATUS_INVALID_INPUT"


def field_docs(p: TanhParams) -> dict[str, list[FieldDoc]]:
    bound = p.k1 + p.k2 + p.k3
    return {
        "input": [
            FieldDoc("R_c", "-", "body -> reference", f"a rotation matrix; {INVALID}", f"body attitude ({DCM})"),
            FieldDoc("w_c", "rad/s", "body", f"any finite; {INVALID}", "body rate"),
            FieldDoc("R_t", "-", "target -> reference", f"a rotation matrix; {INVALID}", f"target attitude ({DCM})"),
            FieldDoc("w_t", "rad/s", "target", f"any finite; {INVALID}", "target rate"),
            FieldDoc("wdot_t", "rad/s^2", "target", f"any finite; {INVALID}", "target angular acceleration"),
        ],
        "output": [
            FieldDoc("torque", "N*m", "body", f"|torque_i| <= k1 + k2 + k3 = {bound:g}, always",
                     "control torque u of eq. 17; hold it for the period"),
            FieldDoc("x1", "-", "body", "|x1| = sin(angle/2) <= 1", "attitude error e (vector part of the error quaternion)"),
            FieldDoc("x2", "rad/s", "body", "0 unless the nominal law ran", "w_e - w_ev (eq. 9)"),
            FieldDoc("varpi", "rad/s", "body", f"|varpi_i| <= {p.varpi_limit:g}", "auxiliary state after this step"),
            FieldDoc("status", "value", "-", "0, STATUS_SINGULAR or STATUS_INVALID_INPUT", "which branch ran"),
        ],
        "state": [
            FieldDoc("varpi", "rad/s", "body", f"|varpi_i| <= {p.varpi_limit:g}; non-finite: reset to 0",
                     "auxiliary system state of eq. 18 (init: 0)"),
        ],
    }


def status_bits() -> list[StatusBit]:
    return [
        StatusBit("STATUS_SINGULAR", STATUS_SINGULAR, "near 180 deg (q0 below q0_min): bounded saturated PD, varpi held"),
        StatusBit("STATUS_INVALID_INPUT", STATUS_INVALID_INPUT,
                  "non-finite input, state or result: zero torque, varpi held"),
    ]
