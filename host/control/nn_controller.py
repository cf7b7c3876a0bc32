"""The controller of paper 001 Fig. 2 in float64: the design reference the generated C is judged by.

Per control period, from the raw Measurement (A_bo, ω_b, target lon/lat, UTC, R_s, V_s):
  1. desired state (host.gnc.guidance, analytic ω_d, ω̇_d) and preprocessing L_bd = L_bo·L_oi·L_di^T,
     A_bd, ω_e = ω_b − ω_d (host.gnc.preprocess);
  2. the 12 network inputs in Table 2 units checked against the artifact's envelope;
  3. inside and valid: mapminmax -> 12-40-3 tansig network (float64, exact tanh) -> reverse
     mapminmax; outside, or any non-finite input: the Table 1 PID law in degrees;
  4. saturation to the wheel limit, NaN -> 0.
Mode logic (identical in the C, codegen/templates/controller.c.j2): the PID takes over at once on
any violation; the network resumes after `dwell_steps` consecutive in-envelope steps (no chatter
at the boundary). The PID integrator runs every step, also while the network flies, with the same
anti-windup, so a hand-over finds it in the state it would have had (bumpless; Table 1 has Ki = 0).
PID inputs that are not finite count as 0 (a failed gyro axis loses its damping term only).
"""
from __future__ import annotations

import functools

import numpy as np

from codegen import artifact as art
from codegen.package.config import PackageConfig
from codegen.units.controller import spec as cs
from host.core.constants import DEG, MU_EARTH, WGS84_A, WGS84_E2
from host.control.batch import BatchLayout, BatchMeasurement, BatchOutput
from host.control.controllers import ControlOutput, Measurement
from host.control.pid import TABLE1_GAINS
from host.errors import HostError
from host.gnc.preprocess import preprocess
from host.plant.spacecraft import TABLE6
from host.core.timebase import gmst_rate

DWELL_STEPS = 10            # 1 s at the 0.1 s control period
INTEGRAL_LIMIT = 100.0      # deg·s; with Table 1's Ki = 0 it only bounds the state


def flight_config(torque_limit: float = TABLE6.torque_limit, control_period: float = 0.1,
                  dwell_steps: int = DWELL_STEPS) -> cs.ControllerConfig:
    """The controller's constants from the host's models (Table 1 gains, WGS-84, the GMST rate)."""
    g = TABLE1_GAINS
    return cs.ControllerConfig(
        kp=tuple(map(float, g.kp)), ki=tuple(map(float, g.ki)), kd=tuple(map(float, g.kd)),
        torque_limit=float(torque_limit), control_period=float(control_period),
        dwell_steps=int(dwell_steps), integral_limit=INTEGRAL_LIMIT,
        earth_a=WGS84_A, earth_e2=WGS84_E2, earth_rate=float(gmst_rate(cs.J2000_JDN, 0.0)), mu=MU_EARTH)


DEFAULT_PACKAGE_NAME = "stare"
CONFIG_SOURCES = {
    "pid": "paper 001 Table 1 (host.control.pid.TABLE1_GAINS); integral limit: host.control.nn_controller",
    "limits": "paper 001 Table 6 (host.plant.spacecraft.TABLE6)",
    "timing": "paper 001: 0.1 s control period; dwell: host.control.nn_controller.DWELL_STEPS",
    "earth": "WGS-84 (host.core.constants); rate: d GMST/dt of IAU-82 (host.core.timebase.gmst_rate)",
}


def default_package_config(name: str = DEFAULT_PACKAGE_NAME) -> PackageConfig:
    """The flight package's default configuration: Table 1 gains, Table 6 limit, the controller unit."""
    return PackageConfig(name, ("controller",), flight_config())


def network64(a: art.Artifact, x: np.ndarray) -> np.ndarray:
    """mapminmax -> MLP -> reverse mapminmax in float64 with the artifact's float32 parameters."""
    im, om = a.input_map, a.output_map
    xn = (x - im.xoffset.astype(float)) * im.gain.astype(float) + float(im.ymin)
    h = np.tanh(a.W1.astype(float) @ xn + a.b1.astype(float))
    yn = a.W2.astype(float) @ h + a.b2.astype(float)
    return (yn - float(om.ymin)) / om.gain.astype(float) + om.xoffset.astype(float)


def clip_torque(v: np.ndarray, limit: float) -> np.ndarray:
    """Per axis to ±limit; NaN -> 0 (never NaN or Inf out)."""
    return np.where(np.isnan(v), 0.0, np.clip(v, -limit, limit))


def bound_flags(env: art.Envelope, x_deg: np.ndarray) -> int:
    """Status bits 1..12: input i outside [min, max] or NaN."""
    with np.errstate(invalid="ignore"):
        bad = ~((x_deg >= env.min.astype(float)) & (x_deg <= env.max.astype(float)))
    return int(sum(1 << (cs.STATUS_BOUND_SHIFT + i) for i in np.flatnonzero(bad)))


def measurement_finite(m: Measurement) -> bool:
    fields = [m.A_bo, m.omega_b, m.R_s, m.V_s, [m.lon, m.lat, m.sec_of_day]]
    return all(np.all(np.isfinite(np.asarray(f, float))) for f in fields)


class ModeLogic:
    """PID at once on a violation; the NN back after dwell_steps consecutive clean steps."""

    def __init__(self, dwell_steps: int):
        self.dwell_steps = dwell_steps
        self.reset()

    def reset(self) -> None:
        self.mode, self.count = cs.MODE_NN, 0

    def update(self, clean: bool) -> int:
        if not clean:
            self.mode, self.count = cs.MODE_PID, 0
        elif self.mode == cs.MODE_PID:
            self.count = min(self.count + 1, self.dwell_steps)
            if self.count >= self.dwell_steps:
                self.mode = cs.MODE_NN
        return self.mode


class TrackingPid:
    """Table 1 PID in degrees whose integrator runs every step (anti-windup on its own output)."""

    def __init__(self, cfg: cs.ControllerConfig):
        self.cfg = cfg
        self.kp, self.ki, self.kd = (np.array(v, float) for v in (cfg.kp, cfg.ki, cfg.kd))
        self.reset()

    def reset(self) -> None:
        self.integral = np.zeros(3)

    def step(self, A_deg: np.ndarray, w_deg: np.ndarray) -> np.ndarray:
        """Unsaturated PID command; advances the integrator."""
        a = np.where(np.isfinite(A_deg), A_deg, 0.0)
        w = np.where(np.isfinite(w_deg), w_deg, 0.0)
        nxt = self.integral + a * self.cfg.control_period
        with np.errstate(over="ignore"):
            raw = -((self.kp * a + self.ki * nxt) + self.kd * w)
        held = np.abs(raw) > self.cfg.torque_limit
        lim = self.cfg.integral_limit
        self.integral = np.where(held, self.integral, np.clip(nxt, -lim, lim))
        return raw


class Fig2Controller:
    """The controller of Fig. 2 around a law of the 12 Table 2 inputs: the law inside the envelope
    (after the dwell), the Table 1 PID outside it, on a non-finite measurement or when the law
    reports its input invalid; then saturation. Subclasses give `law` and the envelope."""

    name = "fig2"
    law_mode = "law"           # ControlOutput.mode while the law flies

    def __init__(self, envelope: art.Envelope, cfg: cs.ControllerConfig):
        self.envelope, self.cfg = envelope, cfg
        self.modes = ModeLogic(cfg.dwell_steps)
        self.pid = TrackingPid(cfg)

    def law(self, x_deg: np.ndarray) -> tuple[np.ndarray, bool]:
        """(torque N·m, input invalid) for the 12 inputs in Table 2 units."""
        raise NotImplementedError

    def reset(self) -> None:
        self.modes.reset()
        self.pid.reset()

    def step(self, m: Measurement) -> ControlOutput:
        valid = measurement_finite(m)
        with np.errstate(all="ignore"):
            x = preprocess(m)
            x_deg = x.network_inputs_deg()
        status = bound_flags(self.envelope, x_deg) | (0 if valid else cs.STATUS_INPUT_INVALID)
        mode = self.modes.update(status == 0)
        raw = self.pid.step(x.A_bd / DEG, x.omega_e / DEG)
        if mode == cs.MODE_NN:
            law, invalid = self.law(x_deg)
            if invalid:
                status |= cs.STATUS_PID | cs.STATUS_INPUT_INVALID
            else:
                raw = law
        else:
            status |= cs.STATUS_PID | (cs.STATUS_DWELL if status == 0 else 0)
        torque = clip_torque(raw, self.cfg.torque_limit)
        if np.any(torque != raw):
            status |= cs.STATUS_SATURATED
        return ControlOutput(torque=torque, mode="pid" if status & cs.STATUS_PID else self.law_mode,
                             info={"A_bd": x.A_bd, "omega_e": x.omega_e, "status": status})


class NnController(Fig2Controller):
    """Fig. 2 in float64 (name "nn"): network inside the envelope, PID fallback, saturation."""

    name = "nn"
    law_mode = "nn"

    def __init__(self, artifact: art.Artifact, cfg: cs.ControllerConfig):
        if artifact.sizes[0] != 12 or artifact.sizes[2] != 3:
            raise HostError(f"the network controller needs a 12-input, 3-output network, got {artifact.shape_text}")
        self.artifact = artifact
        super().__init__(artifact.envelope, cfg)

    def law(self, x_deg: np.ndarray) -> tuple[np.ndarray, bool]:
        return network64(self.artifact, x_deg), False


# ----------------------------------------------------------------------------- batched (rows)

class ModeRows:
    """ModeLogic on rows: the PID at once on a violation, the law back after dwell_steps clean steps."""

    def __init__(self, dwell_steps: int, rows: int):
        self.dwell_steps = dwell_steps
        self.mode = np.full(rows, cs.MODE_NN)
        self.count = np.zeros(rows, dtype=np.int64)

    def update(self, clean: np.ndarray) -> np.ndarray:
        in_pid = self.mode == cs.MODE_PID
        count = np.where(clean & in_pid, np.minimum(self.count + 1, self.dwell_steps), self.count)
        self.count = np.where(clean, count, 0)
        back = clean & in_pid & (self.count >= self.dwell_steps)
        self.mode = np.where(~clean, cs.MODE_PID, np.where(back, cs.MODE_NN, self.mode))
        return self.mode


class TrackingPidRows(TrackingPid):
    """TrackingPid on (R, 3) rows (the same formulas; the gains broadcast over rows)."""

    def reset(self, rows: int = 1) -> None:
        self.integral = np.zeros((rows, 3))


class Fig2Batch:
    """Fig2Controller on rows: the law on the rows inside the envelope (after the dwell), the Table 1
    PID elsewhere, then saturation. Subclasses give `law` on the flying rows and the envelope."""

    variants = 1

    def __init__(self, name: str, envelope: art.Envelope, cfg: cs.ControllerConfig):
        self.name, self.envelope, self.cfg = name, envelope, cfg
        self.lo, self.hi = envelope.min.astype(float), envelope.max.astype(float)

    def law(self, x_deg: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(torque (r, 3) N·m, input invalid (r,)) for r rows of the 12 inputs in Table 2 units."""
        raise NotImplementedError

    def reset(self, layout: BatchLayout) -> None:
        self.modes = ModeRows(self.cfg.dwell_steps, layout.rows)
        self.pid = TrackingPidRows(self.cfg)
        self.pid.reset(layout.rows)

    def step(self, m: BatchMeasurement) -> BatchOutput:
        with np.errstate(all="ignore"):
            x_deg = m.network_inputs_deg()
            inside = np.all((x_deg >= self.lo) & (x_deg <= self.hi), 1)
        mode = self.modes.update(inside & m.finite())
        raw = self.pid.step(m.A_bd / DEG, m.omega_e / DEG)
        flying = np.flatnonzero(mode == cs.MODE_NN)
        if flying.size:
            law, invalid = self.law(x_deg[flying])
            raw[flying[~invalid]] = law[~invalid]
        torque = clip_torque(raw, self.cfg.torque_limit)
        return BatchOutput(torque=torque, saturated=np.any(torque != raw, 1))


def network64_rows(a: art.Artifact, X: np.ndarray) -> np.ndarray:
    """network64 on (r, 12) rows."""
    im, om = a.input_map, a.output_map
    xn = (X - im.xoffset.astype(float)) * im.gain.astype(float) + float(im.ymin)
    h = np.tanh(xn @ a.W1.astype(float).T + a.b1.astype(float))
    yn = h @ a.W2.astype(float).T + a.b2.astype(float)
    return (yn - float(om.ymin)) / om.gain.astype(float) + om.xoffset.astype(float)


class NnBatch(Fig2Batch):
    """NnController on rows (name "nn")."""

    def __init__(self, artifact: art.Artifact, cfg: cs.ControllerConfig):
        if artifact.sizes[0] != 12 or artifact.sizes[2] != 3:
            raise HostError(f"the network controller needs a 12-input, 3-output network, got {artifact.shape_text}")
        self.artifact = artifact
        super().__init__("nn", artifact.envelope, cfg)

    def law(self, x_deg: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        return network64_rows(self.artifact, x_deg), np.zeros(len(x_deg), bool)


@functools.lru_cache(maxsize=4)
def load_artifact(path: str | None) -> art.Artifact:
    """The artifact at `path`; None = the stand-in network fitted to the PID law (host.control.standin)."""
    if path is None:
        from host.control.standin import fit_pid_standin
        return fit_pid_standin(seed=0)
    return art.load(path)


def make_nn_controller(*, torque_limit: float, control_period: float,
                       artifact: str | None = None) -> NnController:
    return NnController(load_artifact(artifact), flight_config(torque_limit, control_period))


def make_nn_batch(*, torque_limit: float, control_period: float, artifact: str | None = None) -> NnBatch:
    return NnBatch(load_artifact(artifact), flight_config(torque_limit, control_period))
