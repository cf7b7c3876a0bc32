"""Golden model of the generated RBF-law step (templates/rbf.c.j2), numpy float32.

Operation for operation and in the same order as the C, vectorised over N independent rows:
every C branch is a mask (np.where), both sides computed, the taken one kept. Sums are written out
left to right (never @, dot or sum); transcendentals are codegen.detmath (sg_math's twin: sinf,
cosf, expf) and the powers |x|^(alpha - 1) the unit's table (pow_abs: codegen/units/tanh/powtab.py
with K = 1, the C's <name>_pow). Constants are codegen/units/rbf/emit.constants32, the float32
values the C carries as hex floats. The step is docs/rbf-backstepping.md section 11; the names
below follow it (e1, e2, nu, z, phi, w_hat, v, u_c, a_b).

Records: codegen/units/rbf/records.py (INPUT_DTYPE, OUTPUT_DTYPE, state_dtype(nodes)).
"""
from __future__ import annotations

import numpy as np

from codegen import detmath
from codegen.golden_vec3 import f32
from codegen.units.rbf import records as rec
from codegen.units.rbf.emit import BOX, Constants32
from codegen.units.tanh.golden import pow_scaled

F32 = np.float32
U32 = np.uint32
STATUS_OK = rec.STATUS_OK
STATUS_INVALID_INPUT = rec.STATUS_INVALID_INPUT
STATUS_FORCE_LIMITED = rec.STATUS_FORCE_LIMITED
STATUS_TORQUE_LIMITED = rec.STATUS_TORQUE_LIMITED
STATUS_WEIGHT_BOUND = rec.STATUS_WEIGHT_BOUND
STATUS_STATE_REPAIRED = rec.STATUS_STATE_REPAIRED
ABS_MASK, EXP_MASK, SIGN_MASK = U32(0x7FFFFFFF), U32(0x7F800000), U32(0x80000000)
ONE_BITS = U32(0x3F800000)     # the command's bound, 1.0


def pow_abs(k: Constants32, ax):
    """|x|^(alpha - 1) for ax = |x| (the C's <name>_pow; +0 and subnormals give 0)."""
    return f32(pow_scaled(ax, k.pow), "pow")


def wrap(k: Constants32, d):
    """One 2 pi correction when d leaves [-pi, pi]."""
    return f32(np.where(d > k.pi, d - k.two_pi, np.where(d < -k.pi, d + k.two_pi, d)), "wrap")


def in_box(k: Constants32, inp) -> np.ndarray:
    """Step 1's valid box (the C compares bit patterns: the same sets, NaN outside every one)."""
    col = lambda name, j: inp[name][:, j]  # noqa: E731
    ok = np.ones(inp.shape[0], dtype=bool)
    for rho in (col("los", 0), col("los_d", 0)):
        ok &= (rho >= k.rho_min) & (rho <= k.rho_max)
    limited = [(col(f, j), getattr(k, lim)) for f, j, lim in BOX]
    for x, lim in limited:
        ok &= np.abs(x) <= lim
    return ok


def repair(bits: np.ndarray, bound_bits):
    """Entry repair of state words given as uint32 bits (N, ...): NaN/Inf -> +0, beyond the bound (the
    column's weight bound, or 1 for the command) -> +-bound. Returns (repaired bits, any repair per row)."""
    m = bits & ABS_MASK
    over = m > bound_bits
    fixed = np.where(m >= EXP_MASK, U32(0), (bits & SIGN_MASK) | bound_bits)
    return np.where(over, fixed, bits).astype(U32), over.reshape(over.shape[0], -1).any(axis=1)


def law(k: Constants32, inp):
    """Everything before the weights: (e, z, vp, rho, cqe, trig) of section 11 steps 2-6."""
    col = lambda name, j: np.ascontiguousarray(inp[name][:, j])  # noqa: E731
    rho, qe, qb = (col("los", j) for j in range(3))
    rhod, qed, qbd = (col("los_rate", j) for j in range(3))
    phi, th, psi = (col("euler", j) for j in range(3))
    w0, w1, w2 = (col("omega", j) for j in range(3))
    rho_r, qe_r, qb_r = (col("los_d", j) for j in range(3))
    rhod_r, qed_r, qbd_r = (col("los_d_rate", j) for j in range(3))
    rhodd_r, qedd_r, qbdd_r = (col("los_d_acc", j) for j in range(3))
    phi_f, th_f, psi_f = (col("euler_d", j) for j in range(3))
    phid_f, thd_f, psid_f = (col("euler_d_rate", j) for j in range(3))
    phidd_f, thdd_f, psidd_f = (col("euler_d_acc", j) for j in range(3))
    # step 2: trigonometry and the Euler rates from omega
    sphi, cphi = detmath.sinf(phi), detmath.cosf(phi)
    sth, cth = detmath.sinf(th), detmath.cosf(th)
    spsi, cpsi = detmath.sinf(psi), detmath.cosf(psi)
    sqe, cqe = detmath.sinf(qe), detmath.cosf(qe)
    sqb, cqb = detmath.sinf(qb), detmath.cosf(qb)
    icphi = F32(1.0) / cphi
    phid = cth * w0 + sth * w2
    psid = (cth * w2 - sth * w0) * icphi
    thd = w1 - sphi * psid
    # step 3: errors
    # the tilt angles (q_eps, phi) differ by at most 2 tilt_max <= 2.8 < pi: no wrap
    e1 = [rho - rho_r, qe - qe_r, wrap(k, qb - qb_r), phi - phi_f, wrap(k, th - th_f), wrap(k, psi - psi_f)]
    sthcphi, cthcphi = sth * cphi, cth * cphi
    wd0 = cth * phid_f - sthcphi * psid_f
    wd1 = thd_f + sphi * psid_f
    wd2 = sth * phid_f + cthcphi * psid_f
    e2 = [rhod - rhod_r, qed - qed_r, qbd - qbd_r, w0 - wd0, w1 - wd1, w2 - wd2]
    e1d3 = cth * e2[3] + sth * e2[5]
    e1d5 = (cth * e2[5] - sth * e2[3]) * icphi
    e1d4 = e2[4] - sphi * e1d5
    e1dot = [e2[0], e2[1], e2[2], e1d3, e1d4, e1d5]
    # step 4: virtual control
    k1s, h = [], []
    for i in range(6):
        a = np.abs(e1[i])
        p = pow_abs(k, a)
        s = e1[i] * p
        eta = np.where(a > k.delta, k.alpha * p, k.eta0)
        k1s.append(f32(k.k1[i] * s))
        h.append(f32((k.k1[i] * eta) * e1dot[i]))
    rk = (cth * k1s[3] - sthcphi * k1s[5], k1s[4] + sphi * k1s[5], sth * k1s[3] + cthcphi * k1s[5])
    sthd, cthd = sth * thd, cth * thd
    rd02 = (sth * sphi) * phid - cthcphi * thd
    rd12 = cphi * phid
    rd22 = -(sthcphi * thd + (cth * sphi) * phid)
    rdk = (rd02 * k1s[5] - sthd * k1s[3], rd12 * k1s[5], cthd * k1s[3] + rd22 * k1s[5])
    rh = (cth * h[3] - sthcphi * h[5], h[4] + sphi * h[5], sth * h[3] + cthcphi * h[5])
    nudot = [-h[0], -h[1], -h[2], -(rdk[0] + rh[0]), -(rdk[1] + rh[1]), -(rdk[2] + rh[2])]
    z = [e2[0] + k1s[0], e2[1] + k1s[1], e2[2] + k1s[2], e2[3] + rk[0], e2[4] + rk[1], e2[5] + rk[2]]
    # step 6: F, A^T e1, sig(z)^alpha, sgn(z)
    qb2 = qbd * qbd
    inv_rho = F32(1.0) / rho
    m2rr = F32(-2.0) * (rhod * inv_rho)
    tqe = sqe / cqe
    F = [(rho * (qed * qed) + (rho * qb2) * (cqe * cqe)) - rhodd_r,
         (m2rr * qed - qb2 * (sqe * cqe)) - qedd_r,
         (m2rr * qbd + ((F32(2.0) * qed) * qbd) * tqe) - qbdd_r]
    gyro = (k.gyro[0] * (w1 * w2), k.gyro[1] * (w2 * w0), k.gyro[2] * (w0 * w1))
    rdf = (rd02 * psid_f - sthd * phid_f, rd12 * psid_f, cthd * phid_f + rd22 * psid_f)
    rff = (cth * phidd_f - sthcphi * psidd_f, thdd_f + sphi * psidd_f, sth * phidd_f + cthcphi * psidd_f)
    F += [(gyro[i] - rdf[i]) - rff[i] for i in range(3)]
    tphi = sphi * icphi
    ate = [e1[0], e1[1], e1[2],
           (cth * e1[3] + (sth * tphi) * e1[4]) - (sth * icphi) * e1[5],
           e1[4],
           (sth * e1[3] - (cth * tphi) * e1[4]) + (cth * icphi) * e1[5]]
    vp = []
    for i in range(6):
        sz = z[i] * pow_abs(k, np.abs(z[i]))
        k3z = np.where(z[i] > F32(0.0), k.k3, np.where(z[i] < F32(0.0), -k.k3, F32(0.0)))
        vp.append(f32((((-F[i] - ate[i]) + nudot[i]) - k.k2[i] * sz) - k3z, "v'"))
    acc = np.abs(vp[0])
    for x in vp[1:] + z:
        acc = acc + np.abs(x)
    result_ok = acc <= k.result_max
    trig = {"sphi": sphi, "cphi": cphi, "sth": sth, "cth": cth, "spsi": spsi, "cpsi": cpsi, "sqe": sqe,
            "cqe": cqe, "sqb": sqb, "cqb": cqb}
    return e1 + e2, z, vp, rho, result_ok, trig


def _gaussians(k: Constants32, s1, s2, c3):
    """exp(max(min(-d_j / (2 sigma^2), 0), -87)), d_j = (S2 - 2 c_j S1) + c3_j for every node j (the C clamps
    on the bits, <name>_exponent: the same values for every t that is not NaN, -0 included)."""
    phi = []
    for j in range(k.nodes):
        t = ((s2 - k.basis_c2[j] * s1) + c3[j]) * k.neg_inv_2s2
        t = np.where(t >= F32(-87.0), t, F32(-87.0))
        t = np.where(t <= F32(0.0), t, F32(0.0))
        phi.append(f32(detmath.expf(f32(t)), "phi"))
    return phi


def basis(k: Constants32, e, command=None):
    """phi_j = exp(max(min(-d_j / (2 sigma^2), 0), -87)), d_j = sum_i (x_i - c_j)^2 = (S2 - 2 c_j S1) + 12 c_j^2,
    x = e / s: S1 = sum x_i, S2 = sum x_i^2 (left to right). With the (repaired) previous command u (6
    columns): also the second network's phi_Delta_j on the 18 inputs [x; u], S1 and S2 continued over u,
    d_j = (S2' - 2 c_j S1') + 18 c_j^2 (= phi_j exp(-|u - c_j|^2 / (2 sigma^2)) mathematically).
    Returns (phi, phi_Delta or None)."""
    s1 = f32(e[0] * k.inv_scale[0])
    s2 = s1 * s1
    for i in range(1, 12):
        x = f32(e[i] * k.inv_scale[i])
        s1 = s1 + x
        s2 = s2 + x * x
    phi = _gaussians(k, s1, s2, k.basis_c3)
    if command is None:
        return phi, None
    for m in range(6):
        u = np.ascontiguousarray(command[:, m])
        s1 = s1 + u
        s2 = s2 + u * u
    return phi, _gaussians(k, s1, s2, k.basis_c3d)


def adapt(k: Constants32, w, phi, z, a, b):
    """(w_hat, new weights, bound hit per row) of one network from repaired weights w (N, nodes, 6)."""
    n = w.shape[0]
    wh = [np.zeros(n, dtype=F32) for _ in range(6)]
    new = np.empty_like(w)
    hit = np.zeros(n, dtype=bool)
    az = [f32(a * z[kk]) for kk in range(6)]
    for j in range(k.nodes):
        for kk in range(6):
            t = w[:, j, kk]
            wh[kk] = f32(wh[kk] + t * phi[j])
            u = f32(b * t + phi[j] * az[kk])
            m = k.theta_max[kk]
            hit |= (u > m) | (u < -m)
            new[:, j, kk] = np.where(u > m, m, np.where(u < -m, -m, u))
    return wh, new, hit


def step(k: Constants32, state: np.ndarray, inp: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """One <name>_step on N independent rows: (outputs (N,), states after (N,))."""
    sdt = rec.state_dtype(k.nodes)
    if state is None or state.dtype != sdt or inp.dtype != rec.INPUT_DTYPE or state.shape != inp.shape \
            or inp.ndim != 1:
        raise ValueError(f"golden rbf: state and input must be (N,) {sdt} / {rec.INPUT_DTYPE} records, got "
                         f"{getattr(state, 'dtype', None)} {getattr(state, 'shape', None)} and {inp.dtype} {inp.shape}")
    n = inp.shape[0]
    bound = k.theta_max_bits.astype(U32)
    with np.errstate(all="ignore"):
        th_bits, rep1 = repair(np.ascontiguousarray(state["theta"]).view(U32).reshape(n, k.nodes, 6), bound)
        td_bits, rep2 = repair(np.ascontiguousarray(state["theta_delta"]).view(U32).reshape(n, k.nodes, 6), bound)
        cmd_bits, rep3 = repair(np.ascontiguousarray(state["command"]).view(U32).reshape(n, 6), ONE_BITS)
        repaired = rep1 | rep2 | rep3
        theta, theta_d, command = th_bits.view(F32), td_bits.view(F32), cmd_bits.view(F32)
        box = in_box(k, inp)
        e, z, vp, rho, result_ok, t = law(k, inp)
        ok = box & result_ok
        phi, phi_d = basis(k, e, command if k.theorem == 2 else None)   # theorem 1: the command never read
        wh, theta_new, hit = adapt(k, theta, phi, z, k.a, k.b)
        v = [f32(vp[i] - wh[i]) for i in range(6)]
        if k.theorem == 2:
            whd, theta_d_new, hit_d = adapt(k, theta_d, phi_d, z, k.a_d, k.b_d)
            v = [f32(v[i] - whd[i]) for i in range(6)]
            hit |= hit_d
        else:
            theta_d_new = theta_d
        u_c = (-v[0], -(rho * v[1]), (rho * t["cqe"]) * v[2])
        torque = [f32(k.inertia[i] * v[3 + i]) for i in range(3)]
        x0 = t["cqe"] * u_c[0] - t["sqe"] * u_c[1]
        x1 = t["sqe"] * u_c[0] + t["cqe"] * u_c[1]
        y0 = t["cqb"] * x0 + t["sqb"] * u_c[2]
        x2 = t["cqb"] * u_c[2] - t["sqb"] * x0
        p0 = t["cpsi"] * y0 + t["spsi"] * x1
        p1 = t["cpsi"] * x1 - t["spsi"] * y0
        r1 = t["cphi"] * p1 + t["sphi"] * x2
        r2 = t["cphi"] * x2 - t["sphi"] * p1
        a_b = (t["cth"] * p0 - t["sth"] * r2, r1, t["sth"] * p0 + t["cth"] * r2)
        force = [f32(k.mass * a_b[i]) for i in range(3)]

        def clip(x, m):
            return np.where(x > m, m, np.where(x < -m, -m, x)), (x > m) | (x < -m)
        status = np.zeros(n, dtype=U32)
        f_lim = np.zeros(n, dtype=bool)
        t_lim = np.zeros(n, dtype=bool)
        for i in range(3):
            force[i], lim = clip(force[i], k.force_max)
            f_lim |= lim
            torque[i], lim = clip(torque[i], k.torque_max)
            t_lim |= lim
        status |= np.where(f_lim, U32(STATUS_FORCE_LIMITED), U32(0))
        status |= np.where(t_lim, U32(STATUS_TORQUE_LIMITED), U32(0))
        status |= np.where(hit, U32(STATUS_WEIGHT_BOUND), U32(0))
        status = np.where(ok, status, U32(STATUS_INVALID_INPUT))
        status |= np.where(repaired, U32(STATUS_STATE_REPAIRED), U32(0))
        # the next step's command input: this step's limited output normalised (|.| <= 1, emit.constants32)
        cmd_new = [f32(force[i] * k.inv_force_max) for i in range(3)] + [f32(torque[i] * k.inv_torque_max)
                                                                          for i in range(3)]
    out = np.zeros(n, dtype=rec.OUTPUT_DTYPE)
    zero = F32(0.0)
    for i in range(3):
        out["force"][:, i] = np.where(ok, force[i], zero)
        out["torque"][:, i] = np.where(ok, torque[i], zero)
    for i in range(6):
        out["w_hat"][:, i] = np.where(ok, wh[i], zero)
    out["status"] = status
    new_state = np.zeros(n, dtype=sdt)
    new_state["theta"] = np.where(ok[:, None, None], theta_new, theta).reshape(n, -1)
    new_state["theta_delta"] = np.where(ok[:, None, None], theta_d_new, theta_d).reshape(n, -1)
    for i in range(6):    # an invalid step: command 0 (the output was 0)
        new_state["command"][:, i] = np.where(ok, cmd_new[i], zero)
    return out, new_state
