"""The gp unit's interface as the flight package's ICD states it (fields and status bits); the limits,
the prior variance and the gain bounds are computed from the parameters, the status bits are
records.py's constants (the C's are emitted from the same numbers). Status macros are named without
the C entry prefix (the ICD adds it)."""
from __future__ import annotations

from codegen.unit import FieldDoc, StatusBit
from codegen.units.gp import records
from codegen.units.gp.emit import constants32
from codegen.units.gp.params import GpLawParams

INVALID = "outside it or non-finite: zero torque and mu, prior variance, upper gains, STATUS_INVALID_INPUT"


def _num(x: float) -> str:
    return f"{float(x):.9g}"


def field_docs(p: GpLawParams) -> dict[str, list[FieldDoc]]:
    c = constants32(p)
    prior = ", ".join(_num(v) for v in c.prior_var)
    lo, hi = p.gp.envelope_min, p.gp.envelope_max
    envelope = ("training data: q_v in [" + ", ".join(f"{_num(a)}..{_num(b)}" for a, b in zip(lo[:3], hi[:3]))
                + "], omega in [" + ", ".join(f"{_num(a)}..{_num(b)}" for a, b in zip(lo[3:6], hi[3:6])) + "] rad/s")
    return {
        "input": [
            FieldDoc("q", "1", "reference -> body, scalar last",
                     f"|q_i| <= {_num(records.Q_MAX)}, |q|^2 in [{_num(records.NORM2_MIN)}, {_num(records.NORM2_MAX)}]"
                     f"; {INVALID}", "measured attitude quaternion; normalised and sign-fixed (q4 >= 0) inside"),
            FieldDoc("omega", "rad/s", "body", f"|omega_i| <= {_num(records.RATE_MAX)}; {INVALID}",
                     "measured body rate w.r.t. the reference (" + envelope + ")"),
            FieldDoc("h_w", "N*m*s", "body", f"|h_w,i| <= {_num(records.MOMENTUM_MAX)}; {INVALID}",
                     "reaction-wheel angular momentum (the gyroscopic term omega x (J_s omega + h_w))"),
        ],
        "output": [
            FieldDoc("torque", "N*m", "body", f"always finite, |torque_i| <= torque_max = {_num(p.torque_max)} "
                     "(STATUS_TORQUE_LIMITED when clipped); 0 on STATUS_INVALID_INPUT",
                     "commanded wheel torque on the body -K1 q_v - K2 omega + omega x (J_s omega + h_w) - mu; "
                     "hold it for the control period"),
            FieldDoc("mu", "N*m", "body", "always finite; 0 on STATUS_INVALID_INPUT; tends to 0 far from the data",
                     "GP mean of the unknown torque d (the law subtracts it)"),
            FieldDoc("var", "(N*m)^2", "body axes", f"always finite, in [0, prior] with prior = ({prior}); the prior "
                     "far from the data and on STATUS_INVALID_INPUT",
                     "GP variance of d per axis (latent, without the measurement noise)"),
            FieldDoc("gains", "N*m, N*m*s/rad", "-", f"K1 in [{_num(p.k1)}, {_num(p.k1_bar)}], K2 in "
                     f"[{_num(p.k2)}, {_num(p.k2_bar)}]; the upper bounds on STATUS_INVALID_INPUT",
                     "the scheduled gains K_i = k_i + (k_i_bar - k_i) max_k var_k / prior_k"),
            FieldDoc("status", "bits", "-", "OR of the STATUS_* bits below; 0: nominal, nothing clamped",
                     "what happened in this step"),
        ],
    }


def status_bits() -> list[StatusBit]:
    return [
        StatusBit("STATUS_INVALID_INPUT", records.STATUS_INVALID_INPUT,
                  "an input outside the valid box or non-finite: zero torque and mu, prior variance, upper gains; "
                  "caller: FDIR on the attitude source if it persists"),
        StatusBit("STATUS_TORQUE_LIMITED", records.STATUS_TORQUE_LIMITED,
                  "a torque component was clipped to torque_max"),
        StatusBit("STATUS_VAR_FLOOR", records.STATUS_VAR_FLOOR,
                  "k_xx - |w|^2 rounded below 0 near an inducing point and was set to 0; telemetry"),
        StatusBit("STATUS_VAR_CEILING", records.STATUS_VAR_CEILING,
                  "a variance exceeded the prior (a variational eigenvalue above 1, or rounding) and was clamped "
                  "to it; telemetry"),
    ]
