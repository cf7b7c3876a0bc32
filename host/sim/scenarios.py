"""Realistic inputs for the generated units' gates and cycle reports, made with the host's models.

codegen knows nothing of the simulator, so the units that need the world take it from here:
  * the controller: `StaringScenario` (codegen.units.controller.vectors.FlightScenario) samples the
    Table 5 pass over the paper's targets, moved to random UTC in 2000-2100, and turns attitude
    and rate errors chosen in S_d into star-sensor and gyro readings (float64 guidance);
  * the tanh law: `Paper000ClosedLoop` (codegen.units.tanh.vectors.ClosedLoop) flies the golden
    step on the rigid body of host.plant.rigid_body, and records the paper-000 example's steps.
`configure_unit(kind, **inputs)` binds a registered unit with these and the host's flight
configuration; it is how the CLI and the simulator obtain units.
"""
from __future__ import annotations

import numpy as np
from scipy.spatial.transform import Rotation

from codegen import units
from codegen.package.config import PackageConfig
from codegen.unit import Batch, Unit
from codegen.units.controller import spec as cs
from codegen.units.controller.emit import INPUT_DTYPE, to_bam
from codegen.units.controller.vectors import Geometry
from codegen.units.tanh.emit import INPUT_DTYPE as TANH_INPUT_DTYPE
from codegen.units.tanh.emit import STATE_DTYPE as TANH_STATE_DTYPE
from codegen.units.tanh.vectors import axis_angle_rotations, input_rows, random_rotations
from host.core.constants import DEG
from host.core.frames import L_oi
from host.errors import HostError
from host.gnc.guidance import desired_state
from host.control.nn_controller import flight_config
from host.plant.orbit import TABLE5_EPOCH, propagate_rk4, table5_initial_state
from host.plant.rigid_body import RigidBody, paper000_disturbance, state
from host.core.rotations import dcm_from_euler312, euler312_from_dcm, frame_rot_z
from host.sim.tanh_example import DISTURBANCE_AMPLITUDE
from host.sim.tanh_in_loop import example_records
from host.sim.targets import central_target, staring_targets
from host.core.timebase import gmst

PASS_SECONDS = 300.0
PASS_STEP = 0.1
DAYS_2000_2100 = 36525


class StaringScenario:
    """The staring pass of paper 001 as the controller unit's FlightScenario."""

    def __init__(self):
        self._states = None
        self.targets = [central_target(), *staring_targets()]

    def pass_states(self) -> np.ndarray:
        """ECI [R, V] every 0.1 s over the first 300 s of the Table 5 orbit (computed once)."""
        if self._states is None:
            self._states = propagate_rk4(table5_initial_state(), PASS_STEP, int(PASS_SECONDS / PASS_STEP))
        return self._states

    def _moved(self, k: np.ndarray, jd, sec, lon, lat) -> Geometry:
        """The pass states k, rotated about z so that the Earth-fixed geometry at (jd, sec) is the
        one of the Table 5 epoch plus k steps."""
        states = self.pass_states()
        delta = gmst(jd, sec) - gmst(TABLE5_EPOCH[0], TABLE5_EPOCH[1] + k * PASS_STEP)
        rot = frame_rot_z(-delta)
        return Geometry(jd, sec, np.einsum("nij,nj->ni", rot, states[k, :3]),
                        np.einsum("nij,nj->ni", rot, states[k, 3:]), lon, lat)

    def geometry(self, rng: np.random.Generator, n: int, far_targets: bool = False) -> Geometry:
        k = rng.integers(0, self.pass_states().shape[0], n)
        pick = rng.integers(0, len(self.targets), n)
        lon = np.array([self.targets[i].lon for i in pick])
        lat = np.array([self.targets[i].lat for i in pick])
        if far_targets:   # up to ~600 km off the central target: ω_d leaves Table 2 near closest approach
            lon = lon + rng.uniform(-6, 6, n) * DEG
            lat = lat + rng.uniform(-3, 3, n) * DEG
        day = rng.integers(0, DAYS_2000_2100, n)
        ms = rng.integers(0, 86_400_000, n)
        return self._moved(k, cs.J2000_JDN + day, ms / 1000.0, lon, lat)

    def sequence_geometry(self, rng: np.random.Generator, steps: int) -> Geometry:
        n_states = self.pass_states().shape[0]
        k = (rng.integers(0, n_states) + np.arange(steps)) % n_states
        tg = self.targets[rng.integers(0, len(self.targets))]
        day, ms0 = rng.integers(0, DAYS_2000_2100), rng.integers(0, 86_400_000 - 100 * steps)
        jd, sec = np.full(steps, cs.J2000_JDN + day), (ms0 + 100 * np.arange(steps)) / 1000.0
        return self._moved(k, jd, sec, np.full(steps, tg.lon), np.full(steps, tg.lat))

    def inputs(self, g: Geometry, A_bd: np.ndarray, omega_e: np.ndarray) -> np.ndarray:
        """Sensor readings that give these errors: L_bo = L_bd L_di L_oi^T, ω_b = ω_e + ω_d (float64)."""
        d = desired_state(g.jd, g.sec, g.R, g.V, g.lon, g.lat)
        L_bo = dcm_from_euler312(A_bd) @ d.L_di @ np.swapaxes(L_oi(g.R, g.V), -1, -2)
        inp = np.zeros(np.shape(g.jd), dtype=INPUT_DTYPE)
        inp["A_bo"], inp["omega_b"] = euler312_from_dcm(L_bo), omega_e + d.omega_d
        inp["R_s"], inp["V_s"] = g.R, g.V
        inp["lon"], inp["lat"] = to_bam(g.lon), to_bam(g.lat)
        inp["utc_day"] = g.jd - cs.J2000_JDN
        inp["utc_ms"] = np.round(g.sec * 1000.0).astype(np.int64)
        return inp


class Paper000ClosedLoop:
    """The tanh unit's ClosedLoop: its golden step flying paper 000's rigid body (the unit's inertia)."""

    def __init__(self, substeps: int = 4, amplitude: float = DISTURBANCE_AMPLITUDE):
        self.substeps, self.amplitude = substeps, amplitude

    def sequences(self, unit, n_seq: int, steps: int, seed: int) -> np.ndarray:
        """From random attitudes (a quarter, at least one, within 1° of 180°), random rates and a
        slowly turning target; the float32 inputs the step saw, (n_seq, steps)."""
        rng = np.random.default_rng(seed)
        period = unit.period
        body = RigidBody(unit.params.inertia, paper000_disturbance(self.amplitude))
        R_t0 = random_rotations(n_seq, rng)
        angle = rng.uniform(0.0, np.pi, n_seq)
        near = max(1, n_seq // 4)
        angle[:near] = np.pi - rng.uniform(0.0, np.radians(1.0), near)  # q0 < q0_min: starts in the fallback
        R = R_t0 @ axis_angle_rotations(angle, rng)
        w = rng.normal(scale=0.1, size=(n_seq, 3))
        w_t = rng.normal(scale=0.002, size=(n_seq, 3)) * (rng.random((n_seq, 1)) < 0.5)
        y = [state(R[i], w[i]) for i in range(n_seq)]
        st = np.zeros(n_seq, dtype=TANH_STATE_DTYPE)
        inputs = np.zeros((n_seq, steps), dtype=TANH_INPUT_DTYPE)
        zero = np.zeros((n_seq, 3))
        h = period / self.substeps
        for s in range(steps):
            t = s * period
            R_t = R_t0 @ Rotation.from_rotvec(w_t * t).as_matrix()
            R_now = np.array([yi[:9] for yi in y]).reshape(n_seq, 3, 3)
            w_now = np.array([yi[9:] for yi in y])
            x = input_rows(R_now, w_now, R_t, w_t, zero).view(TANH_INPUT_DTYPE).reshape(n_seq)
            out, st = unit.golden(st, x)
            inputs[:, s] = x
            for i in range(n_seq):
                u = tuple(float(v) for v in out["torque"][i])
                for j in range(self.substeps):
                    y[i] = body.rk4_step(t + j * h, y[i], h, u)
        return inputs

    def cycle_classes(self, unit) -> dict[str, Batch]:
        """`example`: the (state, input) records of the paper-000 example flown by the golden step."""
        return {"example": example_records(unit.params, unit.period)}


def package_units(cfg: PackageConfig, artifact, params: dict | None = None) -> dict[str, Unit]:
    """The units of a flight package bound to its configuration: the controller `<name>` flying
    the network, and each other configured unit `<name>_<unit>` bound to its parameters
    (`params[unit]`) at the same control period (units that take one)."""
    params = dict(params or {})
    bound = {"controller": configure_unit("controller", artifact=artifact, config=cfg.controller, name=cfg.name)}
    for kind in cfg.param_units:
        if kind not in params:
            raise HostError(f"the configuration's units include \"{kind}\": give its parameter file with "
                            f"--params {kind}=FILE")
        period = cfg.controller.control_period if units.get(kind).takes_period else None
        bound[kind] = configure_unit(kind, params=params.pop(kind), period=period, name=f"{cfg.name}_{kind}")
    for kind in params:
        raise HostError(f"--params {kind}=FILE given, but the configuration's [package] units do not include \"{kind}\"")
    return bound


def unit_inputs(kind: str) -> dict:
    """What the host adds when it binds a unit: the flight configuration and realistic inputs."""
    if kind == "controller":
        return {"config": flight_config(), "scenario": StaringScenario()}
    if kind == "tanh":
        return {"scenario": Paper000ClosedLoop()}
    return {}


def configure_unit(kind: str, /, **inputs) -> Unit:
    """A registered unit bound to the caller's inputs (artifact=, params=, period=, ...) and the host's."""
    return units.configure(kind, **{**unit_inputs(kind), **{k: v for k, v in inputs.items() if v is not None}})
