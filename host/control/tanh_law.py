"""Paper 000's finite-time saturated attitude-tracking law (eq. 4-20), float64 host model.

The law is the hyperbolic-tangent controller (17) with its auxiliary system (18)-(20), built on the
backstepping virtual rate (10)-(11). The adaptive law (16) belongs to the paper's *other*
controller (15) and does not enter (17)-(20): this controller has no adaptive estimate, its only
state is ϖ (varpi) of the auxiliary system. See docs/tanh-controller.md for every choice.

Conventions (paper 000, owned by host.core.rotations): R maps body to reference (active), Ṙ = R[ω]×,
ω in body axes. Errors: R_e = R_tᵀR_c, ω_e = ω_c − R_eᵀω_t.

Performance: a continuous reference run evaluates the law ~320k times, so the law works on plain
Python floats held in tuples (3-vectors: (x, y, z); matrices: three row tuples); numpy per-call
overhead would dominate on 3×3 data. `TanhController` converts numpy inputs at its boundary.

Pure-function shape: `evaluate_law(consts, varpi, R_c, w_c, R_t, w_t, wdot_t) -> LawOutput`
returns the torque and dϖ/dt; the continuous simulation integrates dϖ/dt inside its RK4 stages,
the sampled (flight) version applies `euler_update` once per control period. The generated C
mirrors the sampled version.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import NamedTuple

from codegen.units.tanh.params import (  # noqa: F401 (TanhParamsError, load_params, params_from_mapping: re-exported)
    TanhParams,
    TanhParamsError,
    derived_constants,
    load_params,
    params_from_mapping,
)
from host.errors import HostError

Vec = tuple[float, float, float]
Mat = tuple[Vec, Vec, Vec]

STATUS_OK = 0
STATUS_SINGULAR = 1       # |error| near 180°: E is near-singular, bounded fallback torque, ϖ held
STATUS_INVALID_INPUT = 2  # non-finite input or result: zero torque, ϖ held

ZERO3: Vec = (0.0, 0.0, 0.0)

# ----------------------------------------------------------------------------- parameters

# The parameter file schema and its one validator (TanhParams, load_params, params_from_mapping;
# errors are codegen.units.tanh.params.TanhParamsError) live in codegen.units.tanh.params: the C generator
# reads them and codegen must not import host. Imported above and re-exported.


# ----------------------------------------------------------------------------- derived constants


@dataclass(frozen=True)
class LawConstants:
    """Everything the law needs, precomputed once (the C generator bakes these in)."""

    params: TanhParams
    J: Mat = field(repr=False)
    J_inv: Mat = field(repr=False)
    J_inv_norm: float        # spectral norm ‖J⁻¹‖ = 1/λ_min(J)
    r1: float                # f (11) quadratic patch: value and slope continuous at η
    r2: float
    ua_gain: float           # ‖J⁻¹‖·d_max of (20)
    ua_inner_scale: float    # ‖J⁻¹‖·d_max / n1^γ of (20)


def compile_constants(params: TanhParams) -> LawConstants:
    """The derived constants of codegen.units.tanh.params.derived_constants (the C generator rounds the
    same float64 values to float32), as float tuples."""
    d = derived_constants(params)
    return LawConstants(
        params=params,
        J=_as_mat(d["J"]),
        J_inv=_as_mat(d["J_inv"]),
        J_inv_norm=d["J_inv_norm"],
        r1=d["r1"],
        r2=d["r2"],
        ua_gain=d["ua_gain"],
        ua_inner_scale=d["ua_inner_scale"],
    )


# ----------------------------------------------------------------------------- small vector algebra


def _as_vec(v) -> Vec:
    a, b, c = v
    return (float(a), float(b), float(c))


def _as_mat(m) -> Mat:
    r0, r1, r2 = m
    return (_as_vec(r0), _as_vec(r1), _as_vec(r2))


def _dot(a: Vec, b: Vec) -> float:
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


def _cross(a: Vec, b: Vec) -> Vec:
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


def _matvec(m: Mat, v: Vec) -> Vec:
    return (_dot(m[0], v), _dot(m[1], v), _dot(m[2], v))


def _mat_t_vec(m: Mat, v: Vec) -> Vec:
    """mᵀ v."""
    (a, b, c), (d, e, f), (g, h, i) = m
    x, y, z = v
    return (a * x + d * y + g * z, b * x + e * y + h * z, c * x + f * y + i * z)


# ----------------------------------------------------------------------------- attitude error (eq. 4, 8)


def error_matrix(R_t: Mat, R_c: Mat) -> Mat:
    """R_e = R_tᵀ R_c."""
    cols = tuple(zip(*R_c))
    t_cols = tuple(zip(*R_t))
    return tuple(tuple(_dot(tc, cc) for cc in cols) for tc in t_cols)


def error_vector(R_e: Mat, s: float) -> Vec:
    """Eq. 4: x1 = e = vee(R_e − R_eᵀ) / (2s), s = √(1 + tr R_e) (the error quaternion's vector part)."""
    k = 0.5 / s
    return ((R_e[2][1] - R_e[1][2]) * k, (R_e[0][2] - R_e[2][0]) * k, (R_e[1][0] - R_e[0][1]) * k)


def error_vector_near_180(R_e: Mat) -> Vec:
    """The error quaternion's vector part, valid at and near 180° (largest-diagonal pivot).

    From R_e = (q0² − |e|²)I + 2eeᵀ + 2q0[e]×: 4e_k² = 1 + 2R_kk − tr, 4e_j e_k = R_jk + R_kj.
    The sign follows vee(R_e − R_eᵀ) = 4q0·e (q0 ≥ 0), so it joins eq. 4 continuously.
    """
    tr = R_e[0][0] + R_e[1][1] + R_e[2][2]
    k = max(range(3), key=lambda i: R_e[i][i])
    ek = 0.5 * math.sqrt(max(1.0 + 2.0 * R_e[k][k] - tr, 0.0))
    if ek == 0.0:
        return ZERO3
    skew_part = (R_e[2][1] - R_e[1][2], R_e[0][2] - R_e[2][0], R_e[1][0] - R_e[0][1])
    if skew_part[k] < 0.0:
        ek = -ek
    return tuple(ek if j == k else (R_e[j][k] + R_e[k][j]) / (4.0 * ek) for j in range(3))


def attitude_error(R_e: Mat, q0_min: float) -> tuple[float, Vec, bool]:
    """(q0, x1, regular): the error quaternion (q0 ≥ 0, x1 = e) and whether the law (10)-(20) may run.

    regular is False when q0 ≤ q0_min (E = ½(q0 I + [e]×) near-singular, ln(1 − |e|²) → −∞) or
    the input is so far off SO(3) that 1 − |e|² ≤ q0_min²; x1 then comes from the 180°-safe form.
    """
    one_plus_tr = 1.0 + R_e[0][0] + R_e[1][1] + R_e[2][2]
    if one_plus_tr > 4.0 * q0_min * q0_min:
        s = math.sqrt(one_plus_tr)
        x1 = error_vector(R_e, s)
        if 1.0 - _dot(x1, x1) > q0_min * q0_min:
            return 0.5 * s, x1, True
    return 0.5 * math.sqrt(max(one_plus_tr, 0.0)), error_vector_near_180(R_e), False


def error_jacobian(R_e: Mat, e: Vec, s: float) -> Mat:
    """Eq. 8 as printed: E = (tr(R_e)·I − R_eᵀ + 2eeᵀ) / (2s), with ẋ1 = E ω_e (eq. 5).

    On SO(3) it equals ½(q0·I + [e]×), q0 = s/2, which the law uses (tested equal).
    """
    tr = R_e[0][0] + R_e[1][1] + R_e[2][2]
    k = 0.5 / s
    return tuple(
        tuple(((tr if i == j else 0.0) - R_e[j][i] + 2.0 * e[i] * e[j]) * k for j in range(3))
        for i in range(3)
    )


def jacobian_apply(q0: float, e: Vec, v: Vec) -> Vec:
    """E v = ½(q0 v + e × v)."""
    c = _cross(e, v)
    return (0.5 * (q0 * v[0] + c[0]), 0.5 * (q0 * v[1] + c[1]), 0.5 * (q0 * v[2] + c[2]))


def jacobian_solve(q0: float, e: Vec, v: Vec) -> Vec:
    """E⁻¹ v for E = ½(q0 I + [e]×): (2/(q0² + |e|²))·(q0 v − e × v + e (e·v)/q0); needs q0 ≠ 0."""
    c = _cross(e, v)
    ev_q0 = _dot(e, v) / q0
    k = 2.0 / (q0 * q0 + _dot(e, e))
    return tuple(k * (q0 * v[i] - c[i] + e[i] * ev_q0) for i in range(3))


# ----------------------------------------------------------------------------- virtual rate (eq. 10-11)


def shaping(x: float, gamma: float, eta: float, r1: float, r2: float) -> float:
    """Eq. 11: f(x) = r1·x + r2·sign(x)·x² for |x| ≤ η, sign(x)·|x|^γ otherwise."""
    ax = abs(x)
    if ax <= eta:
        return r1 * x + r2 * x * ax
    return math.copysign(ax ** gamma, x)


def shaping_slope(x: float, gamma: float, eta: float, r1: float, r2: float) -> float:
    """f'(x): r1 + 2·r2·|x| inside η, γ·|x|^(γ−1) outside (continuous at η by the choice of r1, r2)."""
    ax = abs(x)
    if ax <= eta:
        return r1 + 2.0 * r2 * ax
    return gamma * ax ** (gamma - 1.0)


def virtual_rate_target(c: LawConstants, x1: Vec) -> Vec:
    """g(x1) = −β1·x1 − β2·f(x1) + λ·ln(1 − x1ᵀx1)·x1, so that ω_ev = E⁻¹ g (eq. 10) gives ẋ1 = g."""
    p = c.params
    barrier = p.lam * math.log(1.0 - _dot(x1, x1))
    return tuple(
        -p.beta1 * xi - p.beta2 * shaping(xi, p.gamma, p.eta, c.r1, c.r2) + barrier * xi for xi in x1
    )


def virtual_rate_target_rate(c: LawConstants, x1: Vec, x1_dot: Vec) -> Vec:
    """(∂g/∂x1)·ẋ1 with ∂g/∂x1 = −β1 I − β2 diag f'(x1) + λ ln(1 − |x1|²) I − 2λ x1 x1ᵀ/(1 − |x1|²)."""
    p = c.params
    one_minus = 1.0 - _dot(x1, x1)
    barrier = p.lam * math.log(one_minus)
    radial = -2.0 * p.lam * _dot(x1, x1_dot) / one_minus
    return tuple(
        (-p.beta1 - p.beta2 * shaping_slope(x1[i], p.gamma, p.eta, c.r1, c.r2) + barrier) * x1_dot[i]
        + radial * x1[i]
        for i in range(3)
    )


def virtual_rate_derivative(c: LawConstants, q0: float, x1: Vec, w_e: Vec, w_ev: Vec) -> Vec:
    """ω̇_ev = E⁻¹((∂g/∂x1)ẋ1 − Ė ω_ev), the analytic derivative of ω_ev = E⁻¹g along the motion.

    ẋ1 = E ω_e, q̇0 = −½ eᵀω_e, Ė = ½(q̇0 I + [ẋ1]×); ω_ev depends on R_e only, so no ω̇ enters.
    """
    x1_dot = jacobian_apply(q0, x1, w_e)
    q0_dot = -0.5 * _dot(x1, w_e)
    e_dot_w = jacobian_apply(q0_dot, x1_dot, w_ev)  # Ė ω_ev has the same ½(a I + [b]×) form
    dg = virtual_rate_target_rate(c, x1, x1_dot)
    return jacobian_solve(q0, x1, (dg[0] - e_dot_w[0], dg[1] - e_dot_w[1], dg[2] - e_dot_w[2]))


# ----------------------------------------------------------------------------- dynamics term F (eq. 7)


def dynamics_term(c: LawConstants, R_e: Mat, w_c: Vec, w_e: Vec, wdot_t: Vec) -> Vec:
    """F = −ω_c × Jω_c − J(ω_c × ω_e) − J R_eᵀ ω̇_t."""
    gyro = _cross(w_c, _matvec(c.J, w_c))
    transport = _cross(w_c, w_e)
    feed = _mat_t_vec(R_e, wdot_t)
    inner = (transport[0] + feed[0], transport[1] + feed[1], transport[2] + feed[2])
    j_inner = _matvec(c.J, inner)
    return (-gyro[0] - j_inner[0], -gyro[1] - j_inner[1], -gyro[2] - j_inner[2])


# ----------------------------------------------------------------------------- law (17) and auxiliary system (18)-(20)


def saturated_torque(c: LawConstants, varpi: Vec, x1: Vec, x1_dot: Vec) -> Vec:
    """Eq. 17: u = −k1 tanh(ε1 ϖ) − k2 tanh(ε2 x1) − k3 tanh(ε3 ẋ1), ẋ1 = E ω_e; |u_i| ≤ k1+k2+k3."""
    p = c.params
    tanh = math.tanh
    return tuple(
        -p.k1 * tanh(p.eps1 * varpi[i]) - p.k2 * tanh(p.eps2 * x1[i]) - p.k3 * tanh(p.eps3 * x1_dot[i])
        for i in range(3)
    )


def regularised_inverse_square(c: LawConstants, delta_sq: float) -> float:
    """1/(δᵀδ), replaced by 1/(δᵀδ + 0.001) when δᵀδ ≤ 0.001 (section 4.2)."""
    reg = c.params.delta_reg
    if delta_sq <= reg:
        return 1.0 / (delta_sq + reg)
    return 1.0 / delta_sq


def disturbance_compensation(c: LawConstants, delta: Vec) -> Vec:
    """Eq. 20: u_a = ‖J⁻¹‖ d_max · δ/‖δ‖ if ‖δ‖ > n1, else ‖J⁻¹‖ d_max · sig(δ)^γ / n1^γ (element-wise)."""
    norm = math.sqrt(_dot(delta, delta))
    if norm > c.params.n1:
        k = c.ua_gain / norm
        return (k * delta[0], k * delta[1], k * delta[2])
    g, k = c.params.gamma, c.ua_inner_scale
    return tuple(k * math.copysign(abs(d) ** g, d) for d in delta)


def auxiliary_rate(c: LawConstants, varpi: Vec, x1: Vec, x1_dot: Vec, x2: Vec, F: Vec,
                   w_ev_dot: Vec, u: Vec) -> Vec:
    """Eq. 18-19, every term with "+": with a = F − J ω̇_ev + u and δ = x2 − ϖ,

    ϖ̇ = J⁻¹a + [x2ᵀa + x1ᵀẋ1]·δ/(δᵀδ) + k4·δ + (k5 + d_max‖x2‖)·δ/(δᵀδ) + u_a(δ).
    """
    p = c.params
    j_wd = _matvec(c.J, w_ev_dot)
    a = (F[0] - j_wd[0] + u[0], F[1] - j_wd[1] + u[1], F[2] - j_wd[2] + u[2])
    delta = (x2[0] - varpi[0], x2[1] - varpi[1], x2[2] - varpi[2])
    inv_sq = regularised_inverse_square(c, _dot(delta, delta))
    along = (_dot(x2, a) + _dot(x1, x1_dot) + p.k5 + p.d_max * math.sqrt(_dot(x2, x2))) * inv_sq + p.k4
    j_inv_a = _matvec(c.J_inv, a)
    ua = disturbance_compensation(c, delta)
    return tuple(j_inv_a[i] + along * delta[i] + ua[i] for i in range(3))


# ----------------------------------------------------------------------------- the whole law


class LawOutput(NamedTuple):
    torque: Vec          # u (N·m), body axes
    varpi_dot: Vec       # dϖ/dt of the auxiliary system
    status: int          # STATUS_*
    x1: Vec              # attitude error e (eq. 4)
    x2: Vec              # ω_e − ω_ev (eq. 9), rad/s
    w_e: Vec             # ω_e, rad/s


def evaluate_law(c: LawConstants, varpi: Vec, R_c: Mat, w_c: Vec, R_t: Mat, w_t: Vec,
                 wdot_t: Vec) -> LawOutput:
    """Torque (17) and ϖ̇ (18) for state ϖ and inputs (R_c, ω_c, R_t, ω_t, ω̇_t), float tuples.

    Near 180° (q0 < q0_min, E singular) a bounded fallback runs instead; non-finite inputs or
    results give zero torque. In both cases ϖ̇ = 0 (ϖ is held) and the status says so.
    """
    if not _all_finite(varpi, R_c, w_c, R_t, w_t, wdot_t):
        return LawOutput(ZERO3, ZERO3, STATUS_INVALID_INPUT, ZERO3, ZERO3, ZERO3)
    R_e = error_matrix(R_t, R_c)
    w_e = _sub(w_c, _mat_t_vec(R_e, w_t))
    q0, x1, regular = attitude_error(R_e, c.params.q0_min)
    if regular:
        out = _nominal_law(c, varpi, R_e, q0, x1, w_c, w_e, wdot_t)
        return out if _all_finite(out.torque, out.varpi_dot) else _invalid(out)
    out = _fallback_near_180(c, x1, w_e)
    return out if _all_finite(out.torque) else _invalid(out)


def _nominal_law(c: LawConstants, varpi: Vec, R_e: Mat, q0: float, x1: Vec, w_c: Vec, w_e: Vec,
                 wdot_t: Vec) -> LawOutput:
    g = virtual_rate_target(c, x1)
    w_ev = jacobian_solve(q0, x1, g)
    x2 = _sub(w_e, w_ev)
    x1_dot = jacobian_apply(q0, x1, w_e)
    w_ev_dot = virtual_rate_derivative(c, q0, x1, w_e, w_ev)
    F = dynamics_term(c, R_e, w_c, w_e, wdot_t)
    u = saturated_torque(c, varpi, x1, x1_dot)
    varpi_dot = auxiliary_rate(c, varpi, x1, x1_dot, x2, F, w_ev_dot, u)
    return LawOutput(u, varpi_dot, STATUS_OK, x1, x2, w_e)


def _fallback_near_180(c: LawConstants, e: Vec, w_e: Vec) -> LawOutput:
    """Saturated quaternion PD, u = −k2 tanh(ε2 e) − k3 tanh(ε3 ω_e): bounded by k2 + k3, it
    turns the body the short way out of the 180° neighbourhood; ϖ is held (ϖ̇ = 0).
    Damping uses ω_e, not E ω_e, because E ω_e loses the component along e near 180°."""
    p = c.params
    u = tuple(-p.k2 * math.tanh(p.eps2 * e[i]) - p.k3 * math.tanh(p.eps3 * w_e[i]) for i in range(3))
    return LawOutput(u, ZERO3, STATUS_SINGULAR, e, ZERO3, w_e)


def _invalid(out: LawOutput) -> LawOutput:
    return LawOutput(ZERO3, ZERO3, STATUS_INVALID_INPUT, out.x1, out.x2, out.w_e)


def _sub(a: Vec, b: Vec) -> Vec:
    return (a[0] - b[0], a[1] - b[1], a[2] - b[2])


def _all_finite(*groups) -> bool:
    isfinite = math.isfinite
    for g in groups:
        for item in g:
            if isinstance(item, tuple):
                if not (isfinite(item[0]) and isfinite(item[1]) and isfinite(item[2])):
                    return False
            elif not isfinite(item):
                return False
    return True


def euler_update(varpi: Vec, varpi_dot: Vec, period: float, limit: float) -> Vec:
    """The sampled (flight) state update: ϖ_{k+1} = clamp(ϖ_k + T·ϖ̇_k, ±limit) (forward Euler).

    The clamp only stops a diverging ϖ (periods ≥ 0.3 s) from overflowing (float32 in flight):
    beyond |ϖ_i| ≈ 0.1 tanh(ε1 ϖ_i) is saturated anyway.
    """
    return tuple(min(max(varpi[i] + period * varpi_dot[i], -limit), limit) for i in range(3))


# ----------------------------------------------------------------------------- stateful wrapper


class TanhController:
    """The sampled controller with explicit state ϖ (ϖ(0) = 0), as the flight C will run it."""

    def __init__(self, params: TanhParams, period: float):
        if not (period > 0 and math.isfinite(period)):
            raise HostError(f"control period must be > 0 s, got {period!r}")
        self.constants = compile_constants(params)
        self.period = float(period)
        self.varpi: Vec = ZERO3

    def reset(self) -> None:
        self.varpi = ZERO3

    def step(self, R_c, w_c, R_t, w_t=ZERO3, wdot_t=ZERO3) -> LawOutput:
        """One control period: evaluate the law on the current ϖ, then advance ϖ by forward Euler."""
        out = evaluate_law(self.constants, self.varpi, _as_mat(R_c), _as_vec(w_c), _as_mat(R_t),
                           _as_vec(w_t), _as_vec(wdot_t))
        self.varpi = euler_update(self.varpi, out.varpi_dot, self.period, self.constants.params.varpi_limit)
        return out
