"""Golden model of the generated GP-law step (templates/gp.c.j2), numpy float32.

Operation for operation and in the same order as the C, vectorised over N independent rows: every C
branch is a mask (np.where), both sides computed, the taken one kept. Sums are written out left to
right from +0 as the C's accumulators start (never @, dot or sum); e^t is codegen.detmath.expf
(sg_expf, whose fast path the C inlines for t in [-87, 0]); the square root detmath.sqrtf. Constants
are codegen/units/gp/emit.constants32. The step is docs/gp-takeover.md section 11.
"""
from __future__ import annotations

import numpy as np

from codegen import detmath
from codegen.golden_vec3 import f32
from codegen.units.gp import records as rec
from codegen.units.gp.emit import Constants32

F32 = np.float32
U32 = np.uint32
ABS_MASK = U32(0x7FFFFFFF)


def _bits_within(x: np.ndarray, limit: np.float32) -> np.ndarray:
    """|x| <= limit and x not NaN, per element, as the C's bit test (LIMIT - |x| has no sign bit)."""
    return (np.ascontiguousarray(x).view(U32) & ABS_MASK) <= np.float32(limit).view(U32)


def in_box(k: Constants32, inp: np.ndarray) -> np.ndarray:
    """Step 0 without the norm: every field finite and within its limit."""
    ok = _bits_within(inp["q"], k.box["q_max"]).all(axis=1)
    ok &= _bits_within(inp["omega"], k.box["rate_max"]).all(axis=1)
    ok &= _bits_within(inp["h_w"], k.box["momentum_max"]).all(axis=1)
    return ok


def _exponent(k: Constants32, t: np.ndarray) -> np.ndarray:
    """The C's clamp to [-87, 0] on the bits: a clear sign bit -> +0, then the unsigned minimum with
    -87's bits (max(min(t, 0), -87) for every t that is not NaN; a NaN maps as the C maps it)."""
    u = np.ascontiguousarray(t, dtype=F32).view(U32)
    u = u & (U32(0) - (u >> U32(31)))
    u = np.minimum(u, np.float32(k.box["exponent_min"]).view(U32))
    return u.view(F32)


def projection(k: Constants32, x: list[np.ndarray]) -> list[np.ndarray]:
    """w = A' k^, k^_j = e^(t_j), t_j = c_j - 1/2 |x - zt_j|^2 (steps 3-4)."""
    kern = []
    for j in range(k.m):
        d = x[0] - k.zt[j, 0]
        t = d * d
        for i in range(1, 6):
            d = x[i] - k.zt[j, i]
            t = t + d * d
        kern.append(f32(detmath.expf(_exponent(k, k.c[j] - F32(0.5) * t)), "k"))
    w = []
    off = 0
    for i in range(k.m):
        acc = k.a[off] * kern[0]
        for j in range(1, i + 1):
            acc = acc + k.a[off + j] * kern[j]
        w.append(f32(acc, "w"))
        off += i + 1
    return w


def moments(k: Constants32, w: list[np.ndarray]):
    """(|w|^2, means m_k^T w, |R_k^T w|^2) with the C's summation orders (step 5-6 sums): every sum but
    the squares' starts from its first term."""
    ww = w[0] * w[0]
    mean = [k.mw[0, a] * w[0] for a in range(3)]
    for j in range(1, k.m):
        ww = ww + w[j] * w[j]
        mean = [mean[a] + k.mw[j, a] * w[j] for a in range(3)]
    sq = [np.zeros_like(w[0])] * 3
    p = 0
    for i in range(k.m):
        e = [k.rt[p, a] * w[i] for a in range(3)]
        p += 1
        for j in range(i + 1, k.m):
            e = [e[a] + k.rt[p, a] * w[j] for a in range(3)]
            p += 1
        sq = [sq[a] + e[a] * e[a] for a in range(3)]
    return f32(ww, "ww"), [f32(v, "mean") for v in mean], [f32(v, "sq") for v in sq]


def step(k: Constants32, state, inp: np.ndarray):
    """Outputs of N rows (the unit is stateless: state is None and stays None)."""
    if state is not None:
        raise ValueError("unit gp is stateless: state must be None")
    if not isinstance(inp, np.ndarray) or inp.dtype != rec.INPUT_DTYPE:
        raise ValueError(f"golden gp: input must be records of {rec.INPUT_DTYPE}, got "
                         f"{getattr(inp, 'dtype', type(inp).__name__)}")
    n = inp.shape[0]
    out = np.zeros(n, dtype=rec.OUTPUT_DTYPE)
    with np.errstate(all="ignore"):
        q = [np.ascontiguousarray(inp["q"][:, i]) for i in range(4)]
        om = [np.ascontiguousarray(inp["omega"][:, i]) for i in range(3)]
        hw = [np.ascontiguousarray(inp["h_w"][:, i]) for i in range(3)]
        n2 = ((q[0] * q[0] + q[1] * q[1]) + q[2] * q[2]) + q[3] * q[3]
        valid = in_box(k, inp) & (n2 >= k.box["norm2_min"]) & (n2 <= k.box["norm2_max"])
        inv = F32(1.0) / detmath.sqrtf(n2)
        qv = [np.where(q[3] < F32(0.0), -(q[i] * inv), q[i] * inv).astype(F32) for i in range(3)]
        x = [qv[i] * k.g[i] for i in range(3)] + [om[i] * k.g[3 + i] for i in range(3)]
        w = projection(k, x)
        ww, mean, sq = moments(k, w)
        r = k.kxx - ww
        floor = ~(r >= F32(0.0))
        r = np.where(floor, F32(0.0), r).astype(F32)
        status = np.where(floor, U32(rec.STATUS_VAR_FLOOR), U32(0))
        smax = np.zeros(n, dtype=F32)
        mu = []
        for a in range(3):
            v = r + sq[a]
            ceil = ~(v <= k.kxx)
            v = np.where(ceil, k.kxx, v).astype(F32)
            status |= np.where(ceil, U32(rec.STATUS_VAR_CEILING), U32(0))
            s = v * k.inv_kxx
            smax = np.where(s > smax, s, smax).astype(F32)
            out["var"][:, a] = k.var_scale[a] * v
            mu.append(f32(k.mu_scale[a] * mean[a], "mu"))
            out["mu"][:, a] = mu[a]
        k1 = k.k1 + k.dk1 * smax
        k1 = np.where(k1 <= k.k1_bar, k1, k.k1_bar).astype(F32)
        k2 = k.k2 + k.dk2 * smax
        k2 = np.where(k2 <= k.k2_bar, k2, k.k2_bar).astype(F32)
        out["gains"][:, 0], out["gains"][:, 1] = k1, k2
        J = k.inertia
        h = [((J[i, 0] * om[0] + J[i, 1] * om[1]) + J[i, 2] * om[2]) + hw[i] for i in range(3)]
        gy = [om[1] * h[2] - om[2] * h[1], om[2] * h[0] - om[0] * h[2], om[0] * h[1] - om[1] * h[0]]
        tmax = k.torque_max
        for a in range(3):
            tau = f32(((gy[a] - k1 * qv[a]) - k2 * om[a]) - mu[a], "tau")
            limited = (tau > tmax) | (tau < -tmax)
            status |= np.where(limited, U32(rec.STATUS_TORQUE_LIMITED), U32(0))
            out["torque"][:, a] = np.where(tau > tmax, tmax, np.where(tau < -tmax, -tmax, tau))
        out["status"] = status
    # outside the box: nothing compensated, the prior variance, the upper gains
    bad = ~valid
    out["torque"][bad] = F32(0.0)
    out["mu"][bad] = F32(0.0)
    out["var"][bad] = k.prior_var
    out["gains"][bad] = np.array([k.k1_bar, k.k2_bar], dtype=F32)
    out["status"][bad] = U32(rec.STATUS_INVALID_INPUT)
    return out, None
