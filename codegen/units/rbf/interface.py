"""The rbf unit's interface as the flight package's ICD states it (fields and status bits); the box,
limits and weight bounds are computed from the parameters, the status bits are records.py's
constants (the C's are emitted from the same numbers). Status macros are named without the C entry
prefix (the ICD adds it)."""
from __future__ import annotations

from codegen.unit import FieldDoc, StatusBit
from codegen.units.rbf import records
from codegen.units.rbf.params import ANGLE_MAX, RbfParams

INVALID = "outside it or non-finite: zero force, torque and w_hat, weights unchanged, command 0, STATUS_INVALID_INPUT"
LOS = "LOS frame (x_l along the line of sight, C_li = Rz(q_eps) Ry(q_beta))"


def _num(x: float) -> str:
    return f"{float(x):.9g}"


def field_docs(p: RbfParams) -> dict[str, list[FieldDoc]]:
    rho = f"rho in [{_num(p.rho_min)}, {_num(p.rho_max)}] m"
    tilt, ang = _num(p.tilt_max), _num(ANGLE_MAX)
    speed, rate, acc = _num(p.speed_max), _num(p.rate_max), _num(p.accel_max)
    angles = f"|q_eps| <= {tilt}, |q_beta| <= {ang} rad"
    euler = f"|phi| <= {tilt}, |theta|, |psi| <= {ang} rad"
    wmax = ", ".join(_num(x) for x in p.theta_max)
    bound = (f"|theta[6 j + k]| <= theta_max[k], one bound per channel k, theta_max = ({wmax}), after every "
             f"step; on entry a non-finite weight is reset to 0 and one beyond its bound clipped to it "
             f"(STATUS_STATE_REPAIRED)")
    return {
        "input": [
            FieldDoc("los", "m, rad", LOS, f"{rho}, {angles}; {INVALID}",
                     "measured range rho and LOS elevation q_eps and azimuth q_beta"),
            FieldDoc("los_rate", "m/s, rad/s", LOS, f"|rho'| <= {speed} m/s, |q'| <= {rate} rad/s; {INVALID}",
                     "measured rates of (rho, q_eps, q_beta)"),
            FieldDoc("euler", "rad", "body from inertial, zxy (C_bi = Ry(theta) Rx(phi) Rz(psi))",
                     f"{euler}; {INVALID}", "measured attitude (phi, theta, psi)"),
            FieldDoc("omega", "rad/s", "body", f"|omega_i| <= {rate} rad/s; {INVALID}", "measured body rate"),
            FieldDoc("los_d", "m, rad", LOS, f"{rho}, {angles}; {INVALID}", "desired (rho_d, q_eps_d, q_beta_d)"),
            FieldDoc("los_d_rate", "m/s, rad/s", LOS, f"|rho_d'| <= {speed} m/s, |q_d'| <= {rate} rad/s; {INVALID}",
                     "first derivatives of los_d"),
            FieldDoc("los_d_acc", "m/s^2, rad/s^2", LOS, f"|.| <= {acc}; {INVALID}", "second derivatives of los_d"),
            FieldDoc("euler_d", "rad", "desired body from inertial, zxy", f"{euler}; {INVALID}",
                     "desired attitude (phi_f, theta_f, psi_f)"),
            FieldDoc("euler_d_rate", "rad/s", "-", f"|.| <= {rate} rad/s; {INVALID}", "first derivatives of euler_d"),
            FieldDoc("euler_d_acc", "rad/s^2", "-", f"|.| <= {acc} rad/s^2; {INVALID}",
                     "second derivatives of euler_d"),
        ],
        "output": [
            FieldDoc("force", "N", "body", f"always finite, |force_i| <= force_max = {_num(p.force_max)} "
                     "(STATUS_FORCE_LIMITED when clipped); 0 on STATUS_INVALID_INPUT",
                     "commanded thrust m_n C_bi C_li^T u_c; hold it for the control period"),
            FieldDoc("torque", "N*m", "body", f"always finite, |torque_i| <= torque_max = {_num(p.torque_max)} "
                     "(STATUS_TORQUE_LIMITED when clipped); 0 on STATUS_INVALID_INPUT",
                     "commanded torque J_n v_att; hold it for the control period"),
            FieldDoc("w_hat", "m/s^2, rad/s^2 (channels rho, q_eps, q_beta, phi, theta, psi)", "x2-dot channels",
                     f"always finite, |w_hat_k| <= nodes * theta_max[k] ({p.nodes} * ({wmax})); 0 on "
                     "STATUS_INVALID_INPUT",
                     "first network's estimate theta^T phi(e) of the unknown term w, before this step's update"),
            FieldDoc("status", "bits", "-", "OR of the STATUS_* bits below; 0: nominal, nothing limited",
                     "what happened in this step"),
        ],
        "state": [
            FieldDoc("theta", "m/s^2 (k = 0..2), rad/s^2 (k = 3..5) per unit basis value", "x2-dot channels",
                     bound, "weights of the first network, row-major [node j][channel k] (init: 0)"),
            FieldDoc("theta_delta", "as theta", "x2-dot channels",
                     bound + ("" if p.theorem == 2 else "; theorem 1: never read or adapted (0 from init)"),
                     "weights of the second network (G Delta_u, theorem 2), same layout (init: 0)"),
            FieldDoc("command", "1 (force / force_max, torque / torque_max)", "body",
                     "each entry in [-1, 1] after every step; 0 after STATUS_INVALID_INPUT; on entry a non-finite "
                     "entry is reset to 0 and one beyond +-1 clipped to +-1 (STATUS_STATE_REPAIRED)"
                     + ("" if p.theorem == 2 else "; theorem 1: stored, never read"),
                     "this step's limited output normalised: the next step's input of the second network "
                     "(init: 0)"),
        ],
    }


def status_bits() -> list[StatusBit]:
    return [
        StatusBit("STATUS_INVALID_INPUT", records.STATUS_INVALID_INPUT,
                  "an input outside the valid box or non-finite (or the law's intermediate result beyond 1e30): "
                  "zero force, torque and w_hat, weights unchanged, command 0; caller: FDIR on the navigation source "
                  "if it persists"),
        StatusBit("STATUS_FORCE_LIMITED", records.STATUS_FORCE_LIMITED, "a force component was clipped to force_max"),
        StatusBit("STATUS_TORQUE_LIMITED", records.STATUS_TORQUE_LIMITED,
                  "a torque component was clipped to torque_max"),
        StatusBit("STATUS_WEIGHT_BOUND", records.STATUS_WEIGHT_BOUND,
                  "the adaptation clipped a weight to its bound; telemetry (persistent: the bound is active)"),
        StatusBit("STATUS_STATE_REPAIRED", records.STATUS_STATE_REPAIRED,
                  "on entry a weight or command entry was non-finite (reset to 0) or beyond its bound (clipped); "
                  "caller: the state memory was corrupted (FDIR)"),
    ]
