"""Golden model of the generated tanh-law step (codegen/templates/tanh.c.j2), numpy float32.

Operation for operation and in the same order as the C, vectorised across N independent
states: a 3-vector is a tuple of three (N,) float32 arrays, R_e nine of them; every C branch
is a mask (np.where), both sides computed, the taken one kept. Sums are written out left to
right (never @, dot or sum), transcendentals are codegen.detmath (sg_math's twin) for tanhf,
logf_tab and sqrtf (the C's tanh and log are its own inline copies of sg_math's table paths, the
same operations in the same order, the tanh from a table with the sign folded in whose every
intermediate is sg_tanhf's or its exact negation) and pow_scaled below for the powers: the C's own
tables (codegen/units/tanh/powtab.py, K x^y from 128/256 intervals and a quadratic, ≤ 2.5 ulp):
β2|x|^(γ−1) in f (11) (β2 f = x·q, β2 f' = γ·q), ||J⁻¹|| d_max sig(δ)^γ / n1^γ in u_a (20) (±0 for
δ_i = ±0 or subnormal). E⁻¹ is the unit quaternion's (2/m as 2(2 − m), 1/(1 − |x1|²) as 1/q0²),
the torque -k1 ((tanh a + tanh b) + tanh c) when k1 = k2 = k3, the validity sums trees of w_e, ω̇_t
(inputs) and ϖ̇, x1 (outputs): docs/tanh-controller.md, "Generated C". Constants are the float32 values of codegen.tanh_emit.constants32, the
same ones the C carries as hex floats. Every stage asserts float32 (numpy 2 promotes float32
with a float64 scalar).

Records are the structured dtypes of codegen.units.tanh.emit, equal to the C structs:
INPUT_DTYPE {R_c[9], w_c[3], R_t[9], w_t[3], wdot_t[3]}, STATE_DTYPE {varpi[3]},
OUTPUT_DTYPE {torque[3], x1[3], x2[3], varpi[3], status (uint32)}.
"""
from __future__ import annotations

import numpy as np

from codegen import detmath
from codegen.golden_vec3 import f32, v3, v_cross, v_dot, v_sub
from codegen.units.tanh import powtab
from codegen.units.tanh.emit import (INPUT_DTYPE, OUTPUT_DTYPE, STATE_DTYPE, Constants32, compensation_pow,
                                     equal_gains, shaping_pow)
from codegen.units.tanh.powtab import PowTab

F32 = np.float32
STATUS_OK, STATUS_SINGULAR, STATUS_INVALID_INPUT = 0, 1, 2


def mat_vec(m, v):
    return v3((m[0] * v[0] + m[1] * v[1]) + m[2] * v[2], (m[3] * v[0] + m[4] * v[1]) + m[5] * v[2],
              (m[6] * v[0] + m[7] * v[1]) + m[8] * v[2])


def mat_t_vec(m, v):
    return v3((m[0] * v[0] + m[3] * v[1]) + m[6] * v[2], (m[1] * v[0] + m[4] * v[1]) + m[7] * v[2],
              (m[2] * v[0] + m[5] * v[1]) + m[8] * v[2])


def error_matrix(rt, rc):
    """R_e = R_tᵀ R_c, nine (N,) arrays, row-major."""
    return tuple(f32((rt[i] * rc[j] + rt[3 + i] * rc[3 + j]) + rt[6 + i] * rc[6 + j])
                 for i in range(3) for j in range(3))


def e_apply(q0, e, v):
    c = v_cross(e, v)
    return v3(*(F32(0.5) * (q0 * v[i] + c[i]) for i in range(3)))


def e_solve(q0, inv_q0, kk, e, v):
    c = v_cross(e, v)
    ev = v_dot(e, v) * inv_q0
    return v3(*(kk * ((q0 * v[i] - c[i]) + e[i] * ev) for i in range(3)))


def pow_scaled(x, t: PowTab):
    """K x^y from the bits of x (sign included) by powtab's tables, as the C's <name>_pow_*3."""
    u = x.view(np.uint32)
    row = t.rows[((u >> np.uint32(t.shift)) & np.uint32(t.n - 1)).astype(np.intp)]
    z = ((u & np.uint32(0x007FFFFF)) | np.uint32(powtab.Z0)).view(F32)
    ek = t.ek[(u >> np.uint32(23)).astype(np.intp)]
    r = f32((z - row[..., 0]) * row[..., 1], "pow r")
    q = r * (t.p1 * r + t.p0)
    s = row[..., 2] * ek
    return f32(s + s * q, "pow")


def shaping(k: Constants32, x):
    """(β2 f(x), β2 f'(x)) of eq. 11 as the C computes them: q = β2|x|^(γ-1) by the table, β2 f = x q,
    β2 f' = γ q outside η; the patch with β2 folded into its constants inside."""
    ax = np.abs(x)
    inside = ax <= k.eta
    q = pow_scaled(ax, shaping_pow(k))
    bf = np.where(inside, k.br1 * x + (k.br2 * x) * ax, x * q)
    bs = np.where(inside, k.br1 + k.br2x2 * ax, k.gamma * q)
    return f32(bf, "shaping"), f32(bs, "shaping slope")


def force_terms(k: Constants32, re, w_c, w_e, wdot_t, w_ev_dot, u):
    """a = F − J ω̇_ev + u formed as −ω_c×Jω_c − J(ω_c×ω_e + R_eᵀω̇_t + ω̇_ev) + u (one J product)."""
    J = tuple(k.J)
    gyro = v_cross(w_c, mat_vec(J, w_c))
    inner = v_cross(w_c, w_e)
    feed = mat_t_vec(re, wdot_t)
    j_sum = mat_vec(J, v3(*((inner[i] + feed[i]) + w_ev_dot[i] for i in range(3))))
    return v3(*(u[i] - (gyro[i] + j_sum[i]) for i in range(3)))  # = (-gyro - j_sum) + u exactly


def compensation(k: Constants32, delta, dsq):
    norm = detmath.sqrtf(dsq)
    outer = norm > k.n1
    kk = k.ua_gain / norm
    return v3(*(np.where(outer, kk * delta[i], pow_scaled(delta[i], compensation_pow(k))) for i in range(3)))


def nominal(k: Constants32, varpi, re, q0, k_e, x1, nsq, om, w_c, w_e, wdot_t):
    """(u, vdot, x2) of law (10)-(20), as {name}_nominal."""
    inv_q0 = F32(4.0) * k_e
    m = q0 * q0 + nsq  # 1 + O(1e-7): (q0, x1) is a unit quaternion up to rounding
    kk = F32(2.0) * (F32(2.0) - m)  # 2/m to (1 - m)²
    inv_om = inv_q0 * inv_q0  # 1/(1 − |x1|²) = 1/q0²
    barrier = k.lam * detmath.logf_tab(om)
    fs = [shaping(k, x1[i]) for i in range(3)]
    c1 = k.nbeta1 + barrier
    g = v3(*(c1 * x1[i] - fs[i][0] for i in range(3)))
    w_ev = e_solve(q0, inv_q0, kk, x1, g)
    x2 = v_sub(w_e, w_ev)
    x1_dot = e_apply(q0, x1, w_e)
    q0_dot = F32(-0.5) * v_dot(x1, w_e)
    e_dot_w = e_apply(q0_dot, x1_dot, w_ev)
    radial = (k.nlam2 * v_dot(x1, x1_dot)) * inv_om
    dg = v3(*((c1 - fs[i][1]) * x1_dot[i] + radial * x1[i] for i in range(3)))
    dg = v_sub(dg, e_dot_w)
    w_ev_dot = e_solve(q0, inv_q0, kk, x1, dg)
    ta, tb, tc = ([detmath.tanhf(eps * v[i]) for i in range(3)]
                  for eps, v in ((k.eps1, varpi), (k.eps2, x1), (k.eps3, x1_dot)))
    if equal_gains(k):  # -k1 ((tanh a + tanh b) + tanh c)
        u = v3(*(k.nk1 * ((ta[i] + tb[i]) + tc[i]) for i in range(3)))
    else:
        u = v3(*((k.nk1 * ta[i] - k.k2 * tb[i]) - k.k3 * tc[i] for i in range(3)))
    a = force_terms(k, re, w_c, w_e, wdot_t, w_ev_dot, u)
    delta = v_sub(x2, varpi)
    dsq = v_dot(delta, delta)
    rho_den = np.where(dsq <= k.delta_reg, dsq + k.delta_reg, dsq)
    along = ((((v_dot(x2, a) + v_dot(x1, x1_dot)) + k.k5) + k.d_max * detmath.sqrtf(v_dot(x2, x2))) / rho_den) + k.k4
    j_inv_a = mat_vec(tuple(k.J_inv), a)
    ua = compensation(k, delta, dsq)
    vdot = v3(*((j_inv_a[i] + along * delta[i]) + ua[i] for i in range(3)))
    return u, vdot, x2


_SKEW = ((7, 5), (2, 6), (3, 1))  # vee(R_e - R_eᵀ)_k = re[hi] - re[lo]


def error_near_180(re, tr):
    """The error quaternion's vector part by the largest-diagonal pivot, as {name}_error_near_180."""
    k = np.where(re[4] > re[0], 1, 0)
    k = np.where(re[8] > np.where(k == 1, re[4], re[0]), 2, k)
    rkk = np.choose(k, (re[0], re[4], re[8]))
    d = (F32(1.0) + F32(2.0) * rkk) - tr
    ek = F32(0.5) * detmath.sqrtf(np.where(d > F32(0.0), d, F32(0.0)))
    skew = np.choose(k, tuple(re[hi] - re[lo] for hi, lo in _SKEW))
    ek = np.where(skew < F32(0.0), -ek, ek)
    scale = F32(0.25) / ek
    e = []
    for j in range(3):
        off = np.choose(k, tuple(re[3 * j + kk] + re[3 * kk + j] for kk in range(3))) * scale
        e.append(np.where(ek == F32(0.0), F32(0.0), np.where(k == j, ek, off)))
    return v3(*e)


def fallback(k: Constants32, e, w_e):
    return v3(*(k.nk2 * detmath.tanhf(k.eps2 * e[i]) - k.k3 * detmath.tanhf(k.eps3 * w_e[i]) for i in range(3)))


def law(k: Constants32, varpi, rc, w_c, rt, w_t, wdot_t):
    """(u, vdot, x1, x2, status, inputs_ok) as {name}_law; inputs_ok: w_e and wdot_t (and so R_e) finite."""
    re = error_matrix(rt, rc)
    rw = mat_t_vec(re, w_t)
    w_e = v_sub(w_c, rw)
    # every entry of R_e is in a product of w_e; the C sums the six as a tree
    tree = f32(f32(f32(w_e[0] + w_e[1]) + f32(w_e[2] + wdot_t[0])) + f32(wdot_t[1] + wdot_t[2]), "sum")
    inputs_ok = (tree - tree) == F32(0.0)
    tr = (re[0] + re[4]) + re[8]
    opt = F32(1.0) + tr
    upper = opt > k.q0min_sq4
    s = detmath.sqrtf(opt)
    k_e = F32(0.5) / s
    x1 = v3((re[7] - re[5]) * k_e, (re[2] - re[6]) * k_e, (re[3] - re[1]) * k_e)
    nsq = v_dot(x1, x1)
    om = np.where(upper, F32(1.0) - nsq, F32(0.0))
    regular = om > k.q0min_sq
    u_n, vdot_n, x2_n = nominal(k, varpi, re, F32(0.5) * s, k_e, x1, nsq, om, w_c, w_e, wdot_t)
    e_s = error_near_180(re, tr)
    u_s = fallback(k, e_s, w_e)
    zero = np.zeros_like(tr)
    pick = lambda a, b: v3(*(np.where(regular, a[i], b[i]) for i in range(3)))  # noqa: E731
    status = np.where(regular, STATUS_OK, STATUS_SINGULAR).astype(np.uint32)
    return (pick(u_n, u_s), pick(vdot_n, (zero, zero, zero)), pick(x1, e_s),
            pick(x2_n, (zero, zero, zero)), status, inputs_ok)


def sum_is_finite(values) -> np.ndarray:
    """The C's validity test: the float32 sum of the values, left to right, is finite (every value
    finite and no overflow); s - s == 0 exactly when s is finite."""
    acc = values[0]
    for v in values[1:]:
        acc = f32(acc + v, "sum")
    return (acc - acc) == F32(0.0)


def step(k: Constants32, state: np.ndarray, inp: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """One {name}_step on N independent rows: (outputs OUTPUT_DTYPE (N,), new states STATE_DTYPE (N,))."""
    if state.dtype != STATE_DTYPE or inp.dtype != INPUT_DTYPE or state.shape != inp.shape or inp.ndim != 1:
        raise ValueError(f"golden tanh: state and input must be (N,) {STATE_DTYPE} / {INPUT_DTYPE} records, "
                         f"got {state.dtype} {state.shape} and {inp.dtype} {inp.shape}")
    with np.errstate(all="ignore"):
        field = lambda rec, name, j: np.ascontiguousarray(rec[name][:, j])  # noqa: E731
        vec = lambda name: tuple(field(inp, name, j) for j in range(inp.dtype[name].shape[0]))  # noqa: E731
        varpi = tuple(field(state, "varpi", j) for j in range(3))
        state_ok = sum_is_finite(varpi)
        u, vdot, x1, x2, status, inputs_ok = law(k, varpi, vec("R_c"), vec("w_c"), vec("R_t"), vec("w_t"),
                                                 vec("wdot_t"))
        ok = state_ok & inputs_ok
        zero = np.zeros(inp.shape[0], dtype=F32)
        # telemetry too (vdot, x1 finite => u, x2 finite): never NaN or Inf; the C's tree of six
        tree = f32(f32(f32(vdot[0] + vdot[1]) + f32(vdot[2] + x1[0])) + f32(x1[1] + x1[2]), "sum")
        result_ok = (tree - tree) == F32(0.0)
        keep = ok & result_ok
        u = tuple(np.where(keep, c, zero) for c in u)
        vdot = tuple(np.where(keep, c, zero) for c in vdot)
        x1 = tuple(np.where(keep, c, zero) for c in x1)
        x2 = tuple(np.where(keep, c, zero) for c in x2)
        status = np.where(keep, status, np.uint32(STATUS_INVALID_INPUT)).astype(np.uint32)
        varpi = tuple(np.where(state_ok, c, zero) for c in varpi)
        new = []
        for i in range(3):
            v = f32(varpi[i] + k.period * vdot[i], "euler")
            new.append(f32(np.where(v > k.limit, k.limit, np.where(v < -k.limit, -k.limit, v)), "state"))
    new_state = np.zeros(inp.shape[0], dtype=STATE_DTYPE)
    out = np.zeros(inp.shape[0], dtype=OUTPUT_DTYPE)
    for i in range(3):
        new_state["varpi"][:, i] = new[i]
        out["torque"][:, i], out["x1"][:, i], out["x2"][:, i], out["varpi"][:, i] = u[i], x1[i], x2[i], new[i]
    out["status"] = status
    return out, new_state
