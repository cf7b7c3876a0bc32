"""Gate input classes and sequences of the generated RBF-law step (independent (state, input) rows):
  inside     typical operating states of the tracking scenario (rho 50-300 m, angles within the box,
             small rates, errors across Delta) with random weights within their bounds and random
             commands in [-1, 1] (some entries at +-1 exactly, some rows 0 as after init)
  edges      box boundaries exactly, |e1_i| at and around Delta, z_i = 0 (e1_i = e2_i = 0), weights at
             +-bound, commands at +-1, +-0 and one ulp inside, rho at rho_min / rho_max, |q_eps|, |phi|
             at tilt_max, angle differences across +-pi
  outside    one field just outside the box (the next float beyond a limit) -> INVALID_INPUT
  special    NaN, +-Inf, -0, subnormals, +-FLT_MAX in random input, weight and command positions
  state      random-bit weights and commands (NaN payloads, Inf, huge, subnormal, beyond +-1) with inside
             inputs: the entry repair
  saturated  large errors, weights at their bounds, commands at +-1: force, torque and weight clipping
Sequences: smooth synthetic trajectories of the tracking scenario (open loop: the inputs do not
respond to the outputs) over which the weights adapt from 0; the command (the state's last output)
is carried from step to step inside the unit; a persistent error in some of them drives weights
into their bounds. State rows are float32 words: theta, theta_delta (6 nodes words each), command (6).
"""
from __future__ import annotations

import numpy as np

from codegen.unit import Batch, class_sizes
from codegen.units.rbf import records as rec
from codegen.units.rbf.emit import BOX, Constants32

F32 = np.float32
CLASSES = ("inside", "edges", "outside", "special", "state", "saturated")
SPECIAL = np.array([0.0, -0.0, 1e-45, -1e-45, 1.1754942e-38, -1.1754942e-38, 1.1754944e-38,
                    np.inf, -np.inf, np.nan, -np.nan, 3.4028235e38, -3.4028235e38], dtype=F32)
FIELDS = rec.INPUT_DTYPE.names
N_IN = 30


def _index(field: str, j: int) -> int:
    return 3 * FIELDS.index(field) + j


def _wrap(a):
    return (a + np.pi) % (2.0 * np.pi) - np.pi


def _operating(k: Constants32, rng, n: int, err_scale: float = 1.0) -> np.ndarray:
    """(n, 30) float64 inputs of the tracking scenario: desired motion plus errors across decades."""
    x = np.zeros((n, N_IN))
    tilt = min(float(k.tilt_max), 0.5)

    row_scale = np.exp(rng.uniform(np.log(1e-3), 0.0, n)) * err_scale   # from fine tracking to the approach

    def err(scale, size):
        return (np.exp(rng.uniform(np.log(1e-5), np.log(1.0), size)) * scale * row_scale
                * rng.choice([-1.0, 1.0], size))
    rho_d = rng.uniform(50.0, 300.0, n)
    x[:, _index("los_d", 0)] = rho_d
    x[:, _index("los_d", 1)] = rng.uniform(-tilt, tilt, n) * 0.8
    x[:, _index("los_d", 2)] = rng.uniform(-np.pi, np.pi, n)
    x[:, _index("euler_d", 0)] = rng.uniform(-tilt, tilt, n) * 0.8
    x[:, _index("euler_d", 1)] = rng.uniform(-np.pi, np.pi, n)
    x[:, _index("euler_d", 2)] = rng.uniform(-np.pi, np.pi, n)
    x[:, _index("los", 0)] = np.clip(rho_d + err(150.0, n), 50.0, 300.0)
    x[:, _index("los", 1)] = np.clip(x[:, _index("los_d", 1)] + err(0.2, n), -tilt, tilt)
    x[:, _index("los", 2)] = _wrap(x[:, _index("los_d", 2)] + err(0.2, n))
    x[:, _index("euler", 0)] = np.clip(x[:, _index("euler_d", 0)] + err(0.2, n), -tilt, tilt)
    x[:, _index("euler", 1)] = _wrap(x[:, _index("euler_d", 1)] + err(0.2, n))
    x[:, _index("euler", 2)] = _wrap(x[:, _index("euler_d", 2)] + err(0.2, n))
    x[:, _index("los_d_rate", 0)] = rng.uniform(-2.0, 2.0, n)
    for j in (1, 2):
        x[:, _index("los_d_rate", j)] = rng.uniform(-0.02, 0.02, n)
    x[:, _index("los_rate", 0)] = x[:, _index("los_d_rate", 0)] + err(5.0, n)
    for j in (1, 2):
        x[:, _index("los_rate", j)] = x[:, _index("los_d_rate", j)] + err(0.05, n)
    for j in range(3):
        x[:, _index("euler_d_rate", j)] = rng.uniform(-0.02, 0.02, n)
        x[:, _index("euler_d_acc", j)] = rng.uniform(-1e-3, 1e-3, n)
        x[:, _index("los_d_acc", j)] = rng.uniform(-1e-2, 1e-2, n) * (10.0 if j == 0 else 0.01)
    om = _euler_rates_to_omega(x[:, _index("euler", 0)], x[:, _index("euler", 1)],
                               *(x[:, _index("euler_d_rate", j)] for j in range(3)))
    for j in range(3):   # the desired body rate plus an error
        x[:, _index("omega", j)] = om[j] + err(0.1, n)
    return x


def _weights(k: Constants32, rng, n: int, fraction: float = 0.5) -> np.ndarray:
    """(n, 2 * nodes * 6) float32 weights uniform within +-fraction * bound."""
    bound = np.tile(k.theta_max.astype(np.float64), 2 * k.nodes)
    return (rng.uniform(-1.0, 1.0, (n, bound.size)) * fraction * bound).astype(F32)


def _commands(rng, n: int) -> np.ndarray:
    """(n, 6) float32 commands in [-1, 1]: uniform, a fifth of the entries at +-1 exactly (a limited
    output), a tenth of the rows 0 (after init or an invalid step)."""
    u = rng.uniform(-1.0, 1.0, (n, 6))
    u = np.where(rng.random((n, 6)) < 0.2, np.sign(u), u)
    u[rng.random(n) < 0.1] = 0.0
    return u.astype(F32)


def _state(k: Constants32, w: np.ndarray, u: np.ndarray) -> np.ndarray:
    """State rows from weights (n, 12 nodes) and commands (n, 6); theta_delta stays 0 under theorem 1 (any
    value is repaired, never read)."""
    w = np.array(w, dtype=F32)
    if k.theorem == 1:
        w[:, 6 * k.nodes:] = 0.0
    return np.concatenate([w, np.asarray(u, dtype=F32)], axis=1)


def _inside_weights(k, rng, n):
    """Weights from freshly adapted (|theta| ~ 1e-5 bound) to half the bound, row by row."""
    return _weights(k, rng, n, 1.0) * np.exp(rng.uniform(np.log(1e-5), np.log(0.5), (n, 1))).astype(F32)


def _class_inside(k, rng, n):
    return _state(k, _inside_weights(k, rng, n), _commands(rng, n)), _operating(k, rng, n)


def _limits(k: Constants32) -> dict[int, tuple[float, float]]:
    lim = {_index(f, j): (-float(getattr(k, name)), float(getattr(k, name))) for f, j, name in BOX}
    for f in ("los", "los_d"):
        lim[_index(f, 0)] = (float(k.rho_min), float(k.rho_max))
    return lim


def _class_edges(k, rng, n):
    w, u, x = _inside_weights(k, rng, n), _commands(rng, n), _operating(k, rng, n)
    lim = _limits(k)
    keys = sorted(lim)
    quarter = n // 4
    # box boundaries exactly (one to three fields per row)
    for r in range(quarter):
        for col in rng.choice(keys, rng.integers(1, 4), replace=False):
            lo, hi = lim[col]
            x[r, col] = F32(hi) if rng.random() < 0.5 else F32(lo)
    # |e1_i| at and around Delta, and exactly 0 with e2_i = 0 (z_i = 0)
    d = float(k.delta)
    pairs = [("los", "los_d", 0), ("los", "los_d", 1), ("los", "los_d", 2), ("euler", "euler_d", 0),
             ("euler", "euler_d", 1), ("euler", "euler_d", 2)]
    for r in range(quarter, 2 * quarter):
        i = rng.integers(0, 6)
        m, dd, j = pairs[i]
        base = F32(x[r, _index(dd, j)])
        choice = rng.integers(0, 4)
        if choice == 0:
            x[r, _index(m, j)] = base   # e1_i = 0
            if i < 3:
                x[r, _index("los_rate", i)] = x[r, _index("los_d_rate", i)]
            else:   # whole attitude at rest on the desired: z_att = 0
                for jj in range(3):
                    x[r, _index("euler", jj)] = x[r, _index("euler_d", jj)]
                    x[r, _index("omega", jj)] = 0.0
                    x[r, _index("euler_d_rate", jj)] = 0.0
        else:
            target = d * (1.0 + rng.choice([-1e-6, 0.0, 1e-6, -0.1, 0.1])) * rng.choice([-1.0, 1.0])
            x[r, _index(m, j)] = float(base) + target
    # angle differences across +-pi (the wrap)
    for r in range(2 * quarter, 3 * quarter):
        m, dd, j = pairs[rng.integers(2, 6)] if rng.random() < 0.8 else pairs[1]
        if j == 0 and m == "euler" or (m == "los" and j == 1):
            continue
        x[r, _index(dd, j)] = rng.choice([-1.0, 1.0]) * rng.uniform(3.0, 3.5)
        x[r, _index(m, j)] = -np.sign(x[r, _index(dd, j)]) * rng.uniform(2.9, 3.5)
    # weights at +-bound exactly
    bound = np.tile(k.theta_max, 2 * k.nodes)
    at = rng.random(w.shape) < 0.3
    w = np.where(at, bound * rng.choice(np.array([-1.0, 1.0], dtype=F32), w.shape), w).astype(F32)
    # command entries at +-1, +-0 and one ulp inside +-1
    edge = np.array([1.0, -1.0, 0.0, -0.0, np.nextafter(F32(1.0), F32(0.0)), -np.nextafter(F32(1.0), F32(0.0))],
                    dtype=F32)
    u = np.where(rng.random(u.shape) < 0.5, edge[rng.integers(0, edge.size, u.shape)], u).astype(F32)
    return _state(k, w, u), x


def _class_outside(k, rng, n):
    state, x = _class_inside(k, rng, n)
    lim = _limits(k)
    keys = sorted(lim)
    for r in range(n):
        col = keys[r % len(keys)]
        lo, hi = lim[col]
        if rng.random() < 0.5:
            x[r, col] = np.nextafter(F32(hi), F32(np.inf)) if rng.random() < 0.7 else hi * rng.uniform(1.0, 10.0) + 1.0
        else:
            x[r, col] = np.nextafter(F32(lo), F32(-np.inf)) if rng.random() < 0.7 else lo - abs(lo) * rng.uniform(0.0, 9.0) - 1.0
    return state, x


def _class_special(k, rng, n):
    state, x = _class_inside(k, rng, n)
    x = x.astype(F32)
    recs = np.concatenate([state, x], axis=1)
    cols = rng.integers(0, recs.shape[1], n)
    recs[np.arange(n), cols] = SPECIAL[np.arange(n) % SPECIAL.size]
    extra = rng.random(recs.shape) < 0.01
    recs[extra] = SPECIAL[rng.integers(0, SPECIAL.size, int(extra.sum()))]
    return np.ascontiguousarray(recs[:, :state.shape[1]]), recs[:, state.shape[1]:]


def _class_state(k, rng, n):
    _, x = _class_inside(k, rng, n)
    words = rng.integers(0, 2 ** 32, size=(n, 12 * k.nodes + 6), dtype=np.uint64).astype(np.uint32)
    state = words.view(F32).copy()
    # a third of the rows: garbage commands just beyond +-1, NaN or Inf (random bits are mostly far beyond)
    beyond = np.array([np.nextafter(F32(1.0), F32(2.0)), -np.nextafter(F32(1.0), F32(2.0)), 1.5, -3e38, np.nan,
                       np.inf, -np.inf], dtype=F32)
    rows = rng.random(n) < 0.3
    state[rows, 12 * k.nodes:] = beyond[rng.integers(0, beyond.size, (int(rows.sum()), 6))]
    valid = np.concatenate([_weights(k, rng, n, 1.0), _commands(rng, n)], axis=1)
    keep = rng.random(state.shape) < 0.7         # most words valid, some rows entirely valid
    state = np.where(keep, valid, state)
    state[: n // 10] = valid[: n // 10]
    return state, x


def _class_saturated(k, rng, n):
    state = _weights(k, rng, n, 1.0)
    bound = np.tile(k.theta_max, 2 * k.nodes)
    state = np.where(rng.random(state.shape) < 0.5, bound * np.sign(state), state).astype(F32)
    u = _commands(rng, n)
    u = np.where(rng.random(u.shape) < 0.7, np.where(u < 0.0, F32(-1.0), F32(1.0)), u).astype(F32)   # limited
    x = _operating(k, rng, n, err_scale=1.0)
    # large range and attitude errors, fast rates
    x[:, _index("los", 0)] = np.where(rng.random(n) < 0.5, 300.0, 50.0)
    x[:, _index("los_d", 0)] = np.where(x[:, _index("los", 0)] > 100.0, 50.0, 300.0)
    x[:, _index("los_rate", 0)] = rng.uniform(-20.0, 20.0, n)
    for j in range(3):
        x[:, _index("omega", j)] = rng.uniform(-1.0, 1.0, n) * float(k.rate_max)
    # half the rows: e / s at a node's centre (phi_j ~ 1, z of the centre's sign) with that node's
    # weights at the bound of the same sign, so the adaptation clips every node's weights
    half = n // 2
    node = rng.integers(0, k.nodes, half)
    c = k.centres.astype(np.float64)[node] * (1.0 + rng.uniform(-1e-3, 1e-3, half))
    _at_node(k, x[:half], c)
    w = state[:half].reshape(half, 2, k.nodes, 6)
    sign = np.where(c >= 0.0, 1.0, -1.0).astype(F32)
    w[np.arange(half), :, node, :] = (sign[:, None, None] * k.theta_max[None, None, :]).astype(F32)
    return _state(k, state, u), x


def _at_node(k: Constants32, x: np.ndarray, c: np.ndarray) -> None:
    """Rows whose normalised errors e_i / s_i all equal c (in place): e1 = c s[0:6], e2 = c s[6:12]."""
    s = np.array([1.0 / float(v) for v in k.inv_scale])
    x[:, _index("los_d", 0)] = 200.0
    x[:, _index("los", 0)] = 200.0 + c * s[0]
    for j, (m, d) in enumerate((("los", "los_d"), ("los", "los_d"), ("euler", "euler_d"), ("euler", "euler_d"),
                                ("euler", "euler_d"))):
        col = (1, 2, 0, 1, 2)[j]
        x[:, _index(d, col)] = np.clip(x[:, _index(d, col)], -0.5 * float(k.tilt_max), 0.5 * float(k.tilt_max)) \
            if (m, col) in (("los", 1), ("euler", 0)) else x[:, _index(d, col)]
        x[:, _index(m, col)] = x[:, _index(d, col)] + c * s[1 + j]
    for j in range(3):
        x[:, _index("los_rate", j)] = x[:, _index("los_d_rate", j)] + c * s[6 + j]
    om = _euler_rates_to_omega(x[:, _index("euler", 0)], x[:, _index("euler", 1)],
                               *(x[:, _index("euler_d_rate", j)] for j in range(3)))
    # omega - R Theta_f' = c s: the attitude part of e2 (R at the measured angles, as the law's omega_d)
    for j in range(3):
        x[:, _index("omega", j)] = om[j] + c * s[9 + j]


_MAKERS = {"inside": _class_inside, "edges": _class_edges, "outside": _class_outside, "special": _class_special,
           "state": _class_state, "saturated": _class_saturated}


def gate_classes(k: Constants32, n: int, seed: int = 0) -> dict[str, Batch]:
    """n independent (state, input) rows in the six classes (deterministic in seed)."""
    sizes = class_sizes(n, CLASSES, "rbf")
    rng = np.random.default_rng(seed)
    sdt = rec.state_dtype(k.nodes)
    out = {}
    for name, m in zip(CLASSES, sizes):
        state, x = _MAKERS[name](k, rng, m)
        with np.errstate(over="ignore"):
            x = np.ascontiguousarray(np.asarray(x).astype(F32))
        out[name] = Batch(np.ascontiguousarray(np.asarray(state, dtype=F32)).view(sdt).reshape(m),
                          x.view(rec.INPUT_DTYPE).reshape(m))
    return out


def _euler_rates_to_omega(phi, th, dphi, dth, dpsi):
    """omega = R(phi, theta) [phi', theta', psi'] (docs/rbf-backstepping.md section 2)."""
    return (np.cos(th) * dphi - np.sin(th) * np.cos(phi) * dpsi,
            dth + np.sin(phi) * dpsi,
            np.sin(th) * dphi + np.cos(th) * np.cos(phi) * dpsi)


def gate_sequences(k: Constants32, n_seq: int, steps: int, seed: int, period: float) -> np.ndarray:
    """(n_seq, steps) inputs: smooth synthetic tracking trajectories, errors decaying from an initial
    offset to a sinusoid plus (in every third sequence) a persistent bias."""
    rng = np.random.default_rng(seed)
    t = np.arange(steps) * period
    x = np.zeros((n_seq, steps, N_IN))
    tilt = min(float(k.tilt_max), 0.5)
    for s in range(n_seq):
        def sig(amp, w, ph):   # amp sin(w t + ph) and its two derivatives
            a = w * t + ph
            return amp * np.sin(a), amp * w * np.cos(a), -amp * w * w * np.sin(a)

        # every third sequence: an approach with large errors and a persistent bias (weights reach their
        # bounds); the others: fine tracking, errors of 1e-4 .. 1e-2 of the approach's
        level = 1.0 if s % 3 == 0 else float(np.exp(rng.uniform(np.log(1e-4), np.log(1e-2))))

        def err(scale):
            scale = scale * level
            tau = rng.uniform(5.0, 100.0)
            e0 = rng.uniform(-1.0, 1.0) * scale
            amp, w, ph = rng.uniform(0.01, 0.1) * scale, rng.uniform(0.01, 0.3), rng.uniform(0, 2 * np.pi)
            bias = rng.uniform(-0.3, 0.3) * scale if s % 3 == 0 else 0.0
            ex = np.exp(-t / tau)
            return (e0 * ex + amp * np.sin(w * t + ph) + bias,
                    -e0 / tau * ex + amp * w * np.cos(w * t + ph))
        r0 = rng.uniform(100.0, 200.0)
        rho_d, rho_d1, rho_d2 = sig(rng.uniform(0.0, 30.0), rng.uniform(0.005, 0.05), rng.uniform(0, 6.3))
        rho_d = rho_d + r0
        qe_d, qe_d1, qe_d2 = sig(rng.uniform(0.0, tilt * 0.6), rng.uniform(0.005, 0.05), rng.uniform(0, 6.3))
        qb_rate = rng.uniform(-0.02, 0.02)
        qb_d = rng.uniform(-np.pi, np.pi) + qb_rate * t
        phi_f, phi_f1, phi_f2 = sig(rng.uniform(0.0, tilt * 0.6), rng.uniform(0.005, 0.05), rng.uniform(0, 6.3))
        th_f, th_f1, th_f2 = sig(rng.uniform(0.0, 1.0), rng.uniform(0.005, 0.05), rng.uniform(0, 6.3))
        psi_rate = rng.uniform(-0.02, 0.02)
        psi_f = rng.uniform(-np.pi, np.pi) + psi_rate * t
        e_rho, e_rho1 = err(min(100.0, r0 - 55.0))
        e_qe, e_qe1 = err(0.15)
        e_qb, e_qb1 = err(0.15)
        e_phi, e_phi1 = err(0.15)
        e_th, e_th1 = err(0.15)
        e_psi, e_psi1 = err(0.15)
        phi = np.clip(phi_f + e_phi, -tilt, tilt)
        th = th_f + e_th
        row = x[s]
        row[:, _index("los", 0)] = np.clip(rho_d + e_rho, 20.0, 400.0)
        row[:, _index("los", 1)] = np.clip(qe_d + e_qe, -tilt, tilt)
        row[:, _index("los", 2)] = _wrap(qb_d + e_qb)
        row[:, _index("los_rate", 0)] = rho_d1 + e_rho1
        row[:, _index("los_rate", 1)] = qe_d1 + e_qe1
        row[:, _index("los_rate", 2)] = qb_rate + e_qb1
        row[:, _index("euler", 0)] = phi
        row[:, _index("euler", 1)] = _wrap(th)
        row[:, _index("euler", 2)] = _wrap(psi_f + e_psi)
        om = _euler_rates_to_omega(phi, th, phi_f1 + e_phi1, th_f1 + e_th1, psi_rate + e_psi1)
        for j in range(3):
            row[:, _index("omega", j)] = om[j]
        row[:, _index("los_d", 0)] = rho_d
        row[:, _index("los_d", 1)] = qe_d
        row[:, _index("los_d", 2)] = _wrap(qb_d)
        row[:, _index("los_d_rate", 0)] = rho_d1
        row[:, _index("los_d_rate", 1)] = qe_d1
        row[:, _index("los_d_rate", 2)] = qb_rate
        row[:, _index("los_d_acc", 0)] = rho_d2
        row[:, _index("los_d_acc", 1)] = qe_d2
        row[:, _index("los_d_acc", 2)] = 0.0
        row[:, _index("euler_d", 0)] = phi_f
        row[:, _index("euler_d", 1)] = _wrap(th_f)
        row[:, _index("euler_d", 2)] = _wrap(psi_f)
        row[:, _index("euler_d_rate", 0)] = phi_f1
        row[:, _index("euler_d_rate", 1)] = th_f1
        row[:, _index("euler_d_rate", 2)] = psi_rate
        row[:, _index("euler_d_acc", 0)] = phi_f2
        row[:, _index("euler_d_acc", 1)] = th_f2
        row[:, _index("euler_d_acc", 2)] = 0.0
    x = np.ascontiguousarray(x.astype(F32))
    return x.view(rec.INPUT_DTYPE).reshape(n_seq, steps)
