"""One optimal-control problem per sample input S_in (paper 001 section 5), solved by IPOPT.

S_in (12 values, Table 2 units) = [ω_d (°/s), ω̇_d (°/s²), A_bd (°, 3-1-2), ω_e (°/s)].

* Desired sequence: ω_d(t) = ω_d + t·ω̇_d (eq. 13); q_d from eq. (14) with Ω(ω) (eq. 16),
  integrated with the same RK4 step τ as the body (not eq. 15's forward Euler, which drifts),
  starting from the identity [0, 0, 0, 1] (eq. 15's [1, 0, 0, 0] is scalar-first).
* Initial state (eq. 18-19): A_bi = A_bd (desired frame = inertial frame at t = 0),
  ω_b = ω_e + ω_d, wheel momentum h_w = 0 (S_in does not carry it).
* Dynamics: eq. (3)-(4) with wheel momentum (host.plant.spacecraft), no external torque; q commands
  held for T each, RK4 with k steps of τ = T/k per command, n = k·q (eq. 20).
* Transcription: multiple shooting (one state node per command), CasADi SX, IPOPT with the
  exact Hessian and MUMPS; states, torque and objective scaled to O(1).
* Objectives (docs/ocp.md states them in full):
  - ``paper-l1``: eq. (6)-(8) literally, J = k1·mean|A_e| + k2·mean|ω_b − ω_d| over the n+1
    RK4 points (degrees, °/s), absolute values through slack variables, no effort term;
  - ``regularised`` (default): J = k1·mean(φ(A_e)) + k2·mean(φ(ω_rel)) + ρ·mean((M − M_ff)²)
    with φ quadratic (or pseudo-Huber), ω_rel = ω_b − L_bd·ω_d the rate relative to the
    desired frame, and M_ff = I·ω̇_d + ω_d × I·ω_d the torque that flies the desired sequence.

The NLP is built once per (process, thread, config) with S_in as its parameter, and reused.
"""
from __future__ import annotations

import hashlib
import json
import os
import threading
import time
from dataclasses import asdict, dataclass, field

# MUMPS calls BLAS; one thread per solve keeps results bit-identical whatever the worker layout.
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
os.environ.setdefault("OMP_NUM_THREADS", "1")

import casadi as ca  # noqa: E402
import numpy as np  # noqa: E402

from host.learn import ocp_casadi as sym  # noqa: E402
from host.core.constants import DEG  # noqa: E402
from host.errors import HostError  # noqa: E402
from host.plant.spacecraft import TABLE6  # noqa: E402

OBJECTIVES = ("regularised", "paper-l1")
TRACKING_LOSSES = ("quadratic", "pseudo-huber")
N_INPUTS = 12
N_STATE = 10  # q (4), ω (3), h_w (3)
IDENTITY_QUAT = (0.0, 0.0, 0.0, 1.0)
# Part of every config hash: bump it when a code change alters solutions, even in the last bit,
# so that datasets made before the change are refused instead of silently mixed with new shards.
FORMULATION = "multiple-shooting-rk4/1"


@dataclass(frozen=True)
class OcpConfig:
    """Every number that shapes the optimum; its hash identifies a dataset (docs/ocp.md)."""

    objective: str = "regularised"
    command_period: float = 0.1      # T, s: the controller's period, each command held this long
    n_commands: int = 30             # q: horizon q·T = 3 s, longer than the ~2 s closed-loop time constant
    steps_per_command: int = 1       # k: RK4 steps per command, τ = T/k, n = k·q (eq. 20)
    torque_bound: float | None = TABLE6.torque_limit   # N·m per axis; None = unbounded
    k1: float = 1.0                  # weight of the angle error (eq. 8)
    k2: float = 5.0                  # weight of the rate error (eq. 8; SPEC 3)
    effort_weight: float = 1.0 / 289.0   # ρ, regularised only: Kp ≈ sqrt(k1/ρ) = 17 N·m/° (Table 1 x)
    tracking: str = "quadratic"      # regularised only: φ = e² or pseudo-Huber 2δ²(sqrt(1+(e/δ)²)−1)
    huber_angle: float = 0.005       # δ for angles, ° (pseudo-Huber only)
    huber_rate: float = 0.001        # δ for rates, °/s (pseudo-Huber only)
    angle_scale: float = 0.02        # °: Table 2 half-width, scales slacks and the objective
    rate_scale: float = 0.004        # °/s: Table 2 half-width, scales slacks and the objective
    torque_scale: float = 1.0        # N·m per unit of the torque decision variable
    tol: float = 1e-8                # IPOPT tol
    max_iter: int = 200              # IPOPT max_iter
    mu_strategy: str = "adaptive"    # IPOPT barrier update: 8 instead of 11 iterations on paper-l1
    extra_ipopt: tuple = field(default=())   # ((option, value), ...) passed through to IPOPT

    @property
    def step(self) -> float:
        """τ, s."""
        return self.command_period / self.steps_per_command

    @property
    def n_steps(self) -> int:
        """n = k·q (eq. 20)."""
        return self.steps_per_command * self.n_commands

    @property
    def horizon(self) -> float:
        return self.command_period * self.n_commands

    def validate(self) -> "OcpConfig":
        if self.objective not in OBJECTIVES:
            raise HostError(f"unknown objective {self.objective!r}; choose one of {', '.join(OBJECTIVES)}")
        if self.tracking not in TRACKING_LOSSES:
            raise HostError(f"unknown tracking loss {self.tracking!r}; choose one of {', '.join(TRACKING_LOSSES)}")
        positive = {
            "command_period": self.command_period, "n_commands": self.n_commands,
            "steps_per_command": self.steps_per_command, "angle_scale": self.angle_scale,
            "rate_scale": self.rate_scale, "torque_scale": self.torque_scale, "tol": self.tol,
            "max_iter": self.max_iter, "huber_angle": self.huber_angle, "huber_rate": self.huber_rate,
        }
        for name, value in positive.items():
            if not value > 0:
                raise HostError(f"OCP setting {name} must be > 0, got {value}")
        if self.torque_bound is not None and not self.torque_bound > 0:
            raise HostError(f"OCP torque_bound must be > 0 or None, got {self.torque_bound}")
        if min(self.k1, self.k2, self.effort_weight) < 0:
            raise HostError("OCP weights k1, k2, effort_weight must be >= 0")
        if self.k1 == 0 and self.k2 == 0:
            raise HostError("OCP weights k1 and k2 must not both be 0 (nothing would be tracked)")
        return self

    def to_dict(self) -> dict:
        d = asdict(self)
        d["extra_ipopt"] = [list(kv) for kv in self.extra_ipopt]
        return d

    def config_hash(self) -> str:
        """sha256 of the canonical JSON of the settings, the formulation and the inertia they use."""
        payload = {"ocp": self.to_dict(), "formulation": FORMULATION, "inertia": TABLE6.inertia.tolist()}
        return hashlib.sha256(json.dumps(payload, sort_keys=True).encode()).hexdigest()


@dataclass(frozen=True)
class OcpResult:
    command: np.ndarray        # (3,) first command M_cmdseq(1), N·m (eq. 21)
    commands: np.ndarray       # (q, 3) the whole optimal sequence, N·m
    status: str                # IPOPT return status
    success: bool              # IPOPT's own success flag
    iterations: int            # IPOPT iterations
    objective: float           # J at the optimum, unscaled (units of docs/ocp.md)
    solve_time: float          # s, wall clock of the IPOPT call
    solve_cpu: float           # s, process CPU time of the IPOPT call (insensitive to other load)


# ----------------------------------------------------------------------------- the NLP


def _desired_sequence(p_deg, config: OcpConfig):
    """q_d and ω_d (rad/s) at the n+1 RK4 points, as expressions of S_in."""
    w_d0, wdot_d = p_deg[0:3] * DEG, p_deg[3:6] * DEG
    tau = config.step
    q_d = [ca.DM(IDENTITY_QUAT)]
    for j in range(config.n_steps):
        q_d.append(sym.desired_quat_step(q_d[-1], w_d0, wdot_d, j * tau, tau))
    w_d = [sym.desired_rate(w_d0, wdot_d, j * tau) for j in range(config.n_steps + 1)]
    return q_d, w_d


def _initial_state(p_deg):
    """Eq. (18)-(19): body at A_bd from the (inertial = desired) frame, ω_b = ω_e + ω_d, h_w = 0."""
    w_d0, A_bd, w_e = p_deg[0:3] * DEG, p_deg[6:9] * DEG, p_deg[9:12] * DEG
    q_b0 = sym.quat_from_small_rotation_dcm(sym.dcm_from_euler312(A_bd))
    return ca.vertcat(q_b0, w_e + w_d0, ca.DM.zeros(3))


def feedforward_torque(w_d, wdot_d, inertia):
    """M_ff = I·ω̇_d + ω_d × I·ω_d (N·m): the torque that keeps the body on the desired rates."""
    return ca.mtimes(inertia, wdot_d) + ca.cross(w_d, ca.mtimes(inertia, w_d))


def _state_scale(config: OcpConfig) -> np.ndarray:
    """Physical state = scale ⊙ decision variable: q as is, ω in °/s, h_w in units of bound·horizon."""
    h_scale = config.torque_scale * config.horizon
    return np.r_[np.ones(4), np.full(3, DEG), np.full(3, h_scale)]


def _loss(e, delta, config: OcpConfig):
    if config.tracking == "quadratic":
        return e * e
    return 2 * delta * delta * (ca.sqrt(1 + (e / delta) ** 2) - 1)


def _desired_function(config: OcpConfig, inertia) -> ca.Function:
    """S_in -> [q_d at the n+1 RK4 points; ω_d there (rad/s); M_ff at the q commands (N·m)]."""
    k = config.steps_per_command
    s_in = ca.SX.sym("s_in", N_INPUTS)
    q_d, w_d = _desired_sequence(s_in, config)
    wdot_d = s_in[3:6] * DEG
    M_ff = [feedforward_torque(w_d[i * k], wdot_d, inertia) for i in range(config.n_commands)]
    return ca.Function("desired", [s_in], [ca.vertcat(*q_d, *w_d, *M_ff)])


def _shooting(config: OcpConfig, x0, Z, U, scale, inertia, inertia_inv):
    """Multiple shooting: the n+1 RK4 states (nodes and intermediate points) and the continuity gaps."""
    nodes = [x0] + [Z[:, i] * scale for i in range(config.n_commands)]
    fine, continuity = [], []
    for i in range(config.n_commands):
        M = U[:, i] * config.torque_scale
        x = nodes[i]
        fine.append(x)
        for j in range(config.steps_per_command):
            x = sym.rk4_states(lambda s: sym.state_derivative(s, M, inertia, inertia_inv), x, config.step)
            if j < config.steps_per_command - 1:
                fine.append(x)
        continuity.append((nodes[i + 1] - x) / scale)
    fine.append(nodes[-1])
    return fine, continuity


def _mean(block):
    return ca.sum2(ca.sum1(block)) / block.numel()


def _regularised_objective(config: OcpConfig, E, U, Mff):
    """k1·mean φ(A_e) + k2·mean φ(ω_rel) + ρ·mean (M − M_ff)², and its scale J_ref."""
    c = config
    J = c.k1 * _mean(_loss(E[0:3, :], c.huber_angle, c)) + c.k2 * _mean(_loss(E[3:6, :], c.huber_rate, c)) \
        + c.effort_weight * _mean((U * c.torque_scale - Mff) ** 2)
    return J, c.k1 * c.angle_scale ** 2 + c.k2 * c.rate_scale ** 2


def _l1_objective(config: OcpConfig, E, error_scale):
    """Eq. 6-8 with slacks: |e| = s⁺ + s⁻ where e = s⁺ − s⁻, s± ≥ 0 (units of the error scales).

    The error enters one equality, so its derivatives are formed once, and s± only need bounds.
    Returns J, its scale J_ref, the slack symbol and the slack equalities.
    """
    c = config
    S = ca.SX.sym("s", 12, E.size2())
    Es = E / ca.repmat(error_scale, 1, E.size2())
    abs_e = S[0:6, :] + S[6:12, :]
    J = c.k1 * c.angle_scale * _mean(abs_e[0:3, :]) + c.k2 * c.rate_scale * _mean(abs_e[3:6, :])
    return J, c.k1 * c.angle_scale + c.k2 * c.rate_scale, S, ca.vec(Es - S[0:6, :] + S[6:12, :])


def _ipopt_options(config: OcpConfig) -> dict:
    opts = {
        "print_time": False,
        "ipopt.print_level": 0,
        "ipopt.sb": "yes",
        "ipopt.tol": config.tol,
        "ipopt.max_iter": config.max_iter,
        "ipopt.linear_solver": "mumps",
        "ipopt.hessian_approximation": "exact",
        "ipopt.mu_strategy": config.mu_strategy,
    }
    opts.update({f"ipopt.{key}": value for key, value in config.extra_ipopt})
    return opts


class OcpSolver:
    """The parametric NLP for one config: build once, call `solve(s_in)` many times."""

    def __init__(self, config: OcpConfig = OcpConfig()):
        self.config = config.validate()
        self._build()

    # -- construction

    def _build(self) -> None:
        c = self.config
        q, n = c.n_commands, c.n_steps
        inertia, inertia_inv = ca.DM(TABLE6.inertia), ca.DM(TABLE6.inertia_inv)
        scale = _state_scale(c)
        # The desired sequence depends on S_in only: one cheap evaluation per solve, then it
        # enters the NLP as parameters instead of being re-derived inside every Hessian call.
        self._desired = _desired_function(c, inertia)

        p_in = ca.SX.sym("p_in", N_INPUTS)
        Qd, Wd, Mff = ca.SX.sym("q_d", 4, n + 1), ca.SX.sym("w_d", 3, n + 1), ca.SX.sym("m_ff", 3, q)
        p = ca.vertcat(p_in, ca.vec(Qd), ca.vec(Wd), ca.vec(Mff))
        Z = ca.SX.sym("x", N_STATE, q)          # scaled nodes 1..q
        U = ca.SX.sym("u", 3, q)                # scaled commands 0..q-1
        fine, continuity = _shooting(c, _initial_state(p_in), Z, U, scale, inertia, inertia_inv)
        E = ca.horzcat(*[self._errors(fine[j], Qd[:, j], Wd[:, j]) for j in range(n + 1)])

        if c.objective == "paper-l1":
            J, J_ref, S, slack_eq = _l1_objective(c, E, self._error_scale())
            z, g = ca.vertcat(ca.vec(Z), ca.vec(U), ca.vec(S)), ca.vertcat(*continuity, slack_eq)
        else:
            (J, J_ref), S = _regularised_objective(c, E, U, Mff), None
            z, g = ca.vertcat(ca.vec(Z), ca.vec(U)), ca.vertcat(*continuity)

        self.J_ref = float(J_ref)
        self._n_z, self._n_x, self._n_u = z.numel(), Z.numel(), U.numel()
        self._n_eq = g.numel()
        self._n_slack = 0 if S is None else S.numel()
        self._nlp = ca.nlpsol("ocp", "ipopt", {"x": z, "p": p, "f": J / J_ref, "g": g}, _ipopt_options(c))
        self._bounds()
        self._guess = self._guess_function(p, Qd, Wd, Mff, scale, Z, U, S, E)

    def _error_scale(self) -> ca.DM:
        c = self.config
        return ca.DM([c.angle_scale] * 3 + [c.rate_scale] * 3)

    def _errors(self, x, q_d, w_d):
        """Angle error (°) and rate error (°/s) at one RK4 point, per the objective's definition."""
        q_b, w_b = x[0:4], x[4:7]
        L_bd = sym.error_dcm(q_b, q_d)
        a = sym.euler312_error(L_bd)
        if self.config.objective == "paper-l1":
            w = w_b - w_d                       # eq. (7): component difference, as the paper
        else:
            w = sym.relative_rate(L_bd, w_b, w_d)
        return ca.vertcat(a, w) / DEG

    def _bounds(self) -> None:
        c = self.config
        u_max = np.inf if c.torque_bound is None else c.torque_bound / c.torque_scale
        lbz = np.r_[np.full(self._n_x, -np.inf), np.full(self._n_u, -u_max), np.zeros(self._n_slack)]
        ubz = np.r_[np.full(self._n_x, np.inf), np.full(self._n_u, u_max), np.full(self._n_slack, np.inf)]
        self._lbz, self._ubz = lbz, ubz
        self._lbg = self._ubg = np.zeros(self._n_eq)     # every constraint is an equality

    def _guess_function(self, p, Qd, Wd, Mff, scale, Z, U, S, E):
        """Start on the desired sequence with the feed-forward torque (deterministic in S_in)."""
        c = self.config
        k = c.steps_per_command
        u_max = np.inf if c.torque_bound is None else 0.99 * c.torque_bound / c.torque_scale
        nodes = [ca.vertcat(Qd[:, i * k], Wd[:, i * k], ca.DM.zeros(3)) / scale
                 for i in range(1, c.n_commands + 1)]
        Z0 = ca.horzcat(*nodes)
        U0 = ca.fmin(ca.fmax(Mff / c.torque_scale, -u_max), u_max)
        parts = [ca.vec(Z0), ca.vec(U0)]
        if S is not None:
            E0 = ca.substitute(E, ca.vertcat(ca.vec(Z), ca.vec(U)), ca.vertcat(ca.vec(Z0), ca.vec(U0)))
            Es0 = E0 / ca.repmat(self._error_scale(), 1, c.n_steps + 1)
            parts.append(ca.vec(ca.vertcat(ca.fmax(Es0, 0) + 0.01, ca.fmax(-Es0, 0) + 0.01)))
        return ca.Function("guess", [p], [ca.vertcat(*parts)])

    # -- use

    def solve(self, s_in) -> OcpResult:
        s_in = np.asarray(s_in, dtype=float).reshape(-1)
        if s_in.shape != (N_INPUTS,) or not np.all(np.isfinite(s_in)):
            raise HostError(f"S_in must be 12 finite numbers, got shape {s_in.shape}")
        c = self.config
        p = np.r_[s_in, np.asarray(self._desired(s_in)).reshape(-1)]
        z0 = self._guess(p)
        start, start_cpu = time.perf_counter(), time.process_time()
        sol = self._nlp(x0=z0, p=p, lbx=self._lbz, ubx=self._ubz, lbg=self._lbg, ubg=self._ubg)
        elapsed, elapsed_cpu = time.perf_counter() - start, time.process_time() - start_cpu
        stats = self._nlp.stats()
        z = np.asarray(sol["x"]).reshape(-1)
        U = z[self._n_x:self._n_x + self._n_u].reshape(c.n_commands, 3) * c.torque_scale
        return OcpResult(
            command=U[0].copy(),
            commands=U,
            status=str(stats["return_status"]),
            success=bool(stats["success"]),
            iterations=int(stats["iter_count"]),
            objective=float(sol["f"]) * self.J_ref,
            solve_time=elapsed,
            solve_cpu=elapsed_cpu,
        )

    def desired_sequence(self, s_in) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """q_d (n+1, 4), ω_d (n+1, 3) rad/s at the RK4 points, and M_ff (q, 3) N·m at the commands."""
        c = self.config
        n1 = c.n_steps + 1
        v = np.asarray(self._desired(np.asarray(s_in, dtype=float))).reshape(-1)
        q_d = v[:4 * n1].reshape(n1, 4)
        w_d = v[4 * n1:7 * n1].reshape(n1, 3)
        return q_d, w_d, v[7 * n1:].reshape(c.n_commands, 3)

    @property
    def size(self) -> dict:
        return {"variables": self._n_z, "equalities": self._n_eq}


_cache = threading.local()


def solver_for(config: OcpConfig = OcpConfig()) -> OcpSolver:
    """The solver of `config`, built on first use in this process and thread, then reused."""
    solvers = getattr(_cache, "solvers", None)
    if solvers is None:
        solvers = _cache.solvers = {}
    if config not in solvers:
        solvers[config] = OcpSolver(config)
    return solvers[config]


def solve(s_in, config: OcpConfig = OcpConfig()) -> OcpResult:
    """The optimal first command for one S_in (Table 2 units); see OcpResult."""
    return solver_for(config).solve(s_in)
