"""Basilisk (AVS Lab, `bsk`, the optional extra `basilisk`) flying the flight package: the staring
scenario and paper 000's example built in an independent simulator. This is the only module that
imports Basilisk; it does so when a run starts (the import takes seconds, and the extra is optional),
and a missing extra is one line.

Paper 000's example (section 4.2, host.sim.tanh_example): a hub with J of eq. 27 and no orbit, the
law's torque and the example's disturbance d(t) as a body torque (extForceTorque), d evaluated at
the start of each plant step and held over it (staregen's RK4 evaluates it in every stage: at
dt = 5e-4 s the two differ by < 1e-7 N·m); R_c = [NB] = C(σ_BN)ᵀ.

Staring scenario (docs/basilisk.md gives the mapping and the differences measured):
* hub: Table 6 mass and inertia. Basilisk's balanced wheels add only Js·g·gᵀ to the spin axes
  (their back-substitution removes it again), so the hub gets I + Σ Js·g·gᵀ: with the wheels'
  absolute momentum h = Js(Ω + gᵀω) this is exactly staregen's eq. 4 with I and h_w (u_s = −M_c);
* orbit: Table 5's initial state, Earth as a point mass with staregen's μ (two-body, as staregen);
* three orthogonal wheels: u_max = the torque limit, Ω_max·Js = the momentum limit, Js = h_max /
  Ω_max at 6000 rpm, no friction; started with Ω = −gᵀω₀ (h_w = 0, Table 6);
* disturbances of cfg.disturbances, each switchable: the gravity gradient (GravityGradientEffector),
  drag (cannonball drag at r_cp, the band of staregen's exponential table that holds the orbit, air
  co-rotating with staregen's Earth rate), the residual dipole (a centred-dipole field with staregen's
  IGRF coefficients on staregen's GMST-rotating Earth, held by a torque-rod effector); the solar
  radiation torque needs SPICE ephemerides and is refused;
* one dynamics task at staregen's plant step (RK4, Basilisk's default integrator). The models run
  in priority order: the spacecraft integrates to t_j and publishes, the flight module reads that
  state and (at each control instant) steps the package's C, then the wheel effector reads the
  command: a zero-order hold without delay, as in staregen.
* errors: the scenario's error model and the very noise draws of staregen's simulator (same seed,
  same stream): star sensor and gyro at the control instants, wheel bias and noise at every plant
  step, so a difference between the two simulators is a difference of the plant, not of the dice.
"""
from __future__ import annotations

import importlib
from importlib import metadata
from types import SimpleNamespace
from typing import Callable

import numpy as np

from host.control.controllers import Controller, Measurement
from host.core.constants import MU_EARTH
from host.core.rotations import quat_from_dcm
from host.core.timebase import add_seconds
from host.core.vec3 import dcm_from_quat3
from host.errors import HostError
from host.plant import orbit
from host.plant.earth import L_ei, earth_rate_vector
from host.plant.environment import EARTH_RADIUS_DIPOLE, IGRF2015_DIPOLE_NT, WGS84_A, EnvironmentTrack, L_oi, \
    atmosphere_band
from host.plant.spacecraft import saturate_torque
from host.sim import tanh_example as tanh_ex
from host.sim.simulator import SCENARIO_EPOCH, History, SimConfig, environment_track, initial_state, run_noise, sense, \
    true_errors

BSK_VERSION = "2.12.1"
INSTALL_HINT = "pip install -e '.[basilisk]'"
WHEEL_MAX_RPM = 6000.0
_PRIORITY = {"spacecraft": 300, "earth": 290, "environment": 280, "effectors": 270, "flight": 200, "wheels": 100,
             "recorders": 50}
_MODULES = {"messaging": "Basilisk.architecture.messaging", "sysModel": "Basilisk.architecture.sysModel",
            "spacecraft": "Basilisk.simulation.spacecraft",
            "rw": "Basilisk.simulation.reactionWheelStateEffector",
            "gg": "Basilisk.simulation.GravityGradientEffector", "ext": "Basilisk.simulation.extForceTorque",
            "base": "Basilisk.utilities.SimulationBaseClass",
            "grav": "Basilisk.utilities.simIncludeGravBody", "rwf": "Basilisk.utilities.simIncludeRW",
            "atmosphere": "Basilisk.simulation.exponentialAtmosphere", "wind": "Basilisk.simulation.zeroWindModel",
            "drag": "Basilisk.simulation.dragDynamicEffector",
            "field": "Basilisk.simulation.magneticFieldCenteredDipole", "mtb": "Basilisk.simulation.MtbEffector",
            "rbk": "Basilisk.utilities.RigidBodyKinematics", "helpers": "Basilisk.utilities.simHelpers"}
_loaded: SimpleNamespace | None = None


def basilisk() -> SimpleNamespace:
    """Basilisk's modules (imported once); HostError in one line when the extra is missing."""
    global _loaded
    if _loaded is None:
        try:
            version = metadata.version("bsk")
            mods = {k: importlib.import_module(v) for k, v in _MODULES.items()}
        except Exception:   # PackageNotFoundError, ImportError, or a broken install
            raise HostError(f"Basilisk is not installed (the optional extra `basilisk`: {INSTALL_HINT})") from None
        if version != BSK_VERSION:
            raise HostError(f"Basilisk {version} is installed; staregen is checked against bsk=={BSK_VERSION} "
                            f"({INSTALL_HINT})")
        _loaded = SimpleNamespace(**mods)
    return _loaded


def _nanos(seconds: float) -> int:
    return int(round(seconds * 1e9))


# ----------------------------------------------------------------------------- the flight module

def _module_class(bsk: SimpleNamespace):
    """A Python SysModel that calls `drive(j, sc_state) -> body torque` every dynamics step and
    writes the wheels' motor torques (u_s = −M, wheels along the body axes) or a body torque."""

    class FlightModule(bsk.sysModel.SysModel):
        def __init__(self, drive: Callable, wheels: bool):
            super().__init__()
            self.drive, self.wheels, self.j = drive, wheels, 0
            self.scStateInMsg = bsk.messaging.SCStatesMsgReader()
            self.rwMotorTorqueOutMsg = bsk.messaging.ArrayMotorTorqueMsg()
            self.cmdTorqueOutMsg = bsk.messaging.CmdTorqueBodyMsg()

        def Reset(self, CurrentSimNanos):   # noqa: N802, N803 (Basilisk's names)
            self.j = 0

        def UpdateState(self, CurrentSimNanos):   # noqa: N802, N803
            torque = self.drive(self.j, self.scStateInMsg())
            self.j += 1
            if self.wheels:
                payload = bsk.messaging.ArrayMotorTorqueMsgPayload()
                payload.motorTorque = [-float(x) for x in torque]
                self.rwMotorTorqueOutMsg.write(payload, CurrentSimNanos, self.moduleID)
            else:
                payload = bsk.messaging.CmdTorqueBodyMsgPayload()
                payload.torqueRequestBody = [float(x) for x in torque]
                self.cmdTorqueOutMsg.write(payload, CurrentSimNanos, self.moduleID)

    class EarthModule(bsk.sysModel.SysModel):
        """Earth's orientation (staregen's GMST rotation) as the planet message the environment reads."""

        def __init__(self, plant_step: float):
            super().__init__()
            self.plant_step, self.j = plant_step, 0
            self.planetOutMsg = bsk.messaging.SpicePlanetStateMsg()

        def Reset(self, CurrentSimNanos):   # noqa: N802, N803
            self.j = 0

        def UpdateState(self, CurrentSimNanos):   # noqa: N802, N803
            payload = bsk.messaging.SpicePlanetStateMsgPayload()
            payload.PlanetName = "earth"
            payload.J20002Pfix = L_ei(*add_seconds(*SCENARIO_EPOCH, self.j * self.plant_step)).tolist()
            self.j += 1
            self.planetOutMsg.write(payload, CurrentSimNanos, self.moduleID)

    return SimpleNamespace(flight=FlightModule, earth=EarthModule)


def _flight_module(bsk, sim, task: str, drive: Callable, body, wheels: bool, tag: str):
    """The flight module reading `body`'s state, in the task after the dynamics and before the actuators."""
    module = _module_class(bsk).flight(drive, wheels=wheels)
    module.ModelTag = tag
    module.scStateInMsg.subscribeTo(body.scStateOutMsg)
    sim.AddModelToTask(task, module, _PRIORITY["flight"])
    return module


def _execute(sim, seconds: float) -> None:
    sim.InitializeSimulation()
    sim.ConfigureStopTime(_nanos(seconds))
    sim.ExecuteSimulation()


# ----------------------------------------------------------------------------- staring scenario

class _StaringDrive:
    """What the flight computer and the wheels' drive electronics do each dynamics step j: at the
    control instants, sense (scenario errors) and step the controller; at every step, the wheels'
    torque = saturated command + bias + noise (staregen's wheel model)."""

    def __init__(self, controller: Controller, lon: float, lat: float, cfg: SimConfig, stream: int, n: int):
        self.controller, self.lon, self.lat, self.cfg = controller, lon, lat, cfg
        self.noise = run_noise(cfg, cfg.seed, stream)
        self.sub = cfg.substeps
        self.cmd = np.zeros(3)
        self.rec_cmd = np.zeros((n + 1, 3))
        self.mode = np.empty(n + 1, dtype=object)

    def measurement(self, j: int, st, bsk) -> Measurement:
        t = j * self.cfg.plant_step
        R, V = np.array(st.r_BN_N, float), np.array(st.v_BN_N, float)
        L_bi = np.array(bsk.rbk.MRP2C(np.array(st.sigma_BN, float)), float)
        k = j // self.sub
        return sense(L_bi, L_oi(R, V), np.array(st.omega_BN_B, float), R, V, *add_seconds(*SCENARIO_EPOCH, t), t,
                     self.noise.star[k], self.noise.gyro[k], self.lon, self.lat, self.cfg)

    def __call__(self, j: int, st) -> np.ndarray:
        bsk = basilisk()
        if j % self.sub == 0 and j < len(self.mode) - 1:
            out = self.controller.step(self.measurement(j, st, bsk))
            self.cmd = np.asarray(out.torque, float)
            self.mode[j:j + self.sub] = out.mode
        applied = saturate_torque(self.cmd, self.cfg.spacecraft.torque_limit)
        if self.cfg.wheel_errors and j < len(self.mode) - 1:
            applied = (applied + self.cfg.errors.wheels.bias_array) + self.noise.wheels[j]
        self.rec_cmd[j] = self.cmd
        return applied


def disturbance_names(cfg: SimConfig) -> list[str]:
    """The disturbances a run of `cfg` has (both simulators: the same DisturbanceParams)."""
    p = cfg.disturbances
    if not cfg.external_torques:
        return []
    return [name for name, on in (("gravity gradient", p.gravity_gradient), ("drag", p.drag_area > 0),
                                  ("magnetic", bool(np.any(p.residual_dipole != 0))),
                                  ("solar radiation", p.srp_area > 0)) if on]


def _add_disturbances(bsk, sim, task: str, sc, earth, cfg: SimConfig) -> list:
    """Basilisk's effectors for the disturbances of cfg.disturbances; returns the Python-side objects that
    must outlive the set-up (Basilisk keeps references to their messages only)."""
    p, kept, names = cfg.disturbances, [], disturbance_names(cfg)
    if "solar radiation" in names:
        raise HostError("Basilisk here has no solar-radiation torque (it needs SPICE ephemerides); switch it off "
                        "(srp_area = 0) on both sides")
    if "gravity gradient" in names:
        gg = bsk.gg.GravityGradientEffector()
        gg.ModelTag = sc.ModelTag
        gg.addPlanetName(earth.planetName)
        sc.addDynamicEffector(gg)
        sim.AddModelToTask(task, gg, _PRIORITY["effectors"])
        kept.append(gg)
    if "drag" not in names and "magnetic" not in names:
        return kept
    planet = _module_class(bsk).earth(cfg.plant_step)
    planet.ModelTag = "staregen_earth"
    sim.AddModelToTask(task, planet, _PRIORITY["earth"])
    kept.append(planet)
    if "drag" in names:
        kept += _add_drag(bsk, sim, task, sc, planet, p)
    if "magnetic" in names:
        kept += _add_residual_dipole(bsk, sim, task, sc, planet, p)
    return kept


def _add_drag(bsk, sim, task: str, sc, planet, p) -> list:
    """staregen's flat-plate drag: Basilisk's cannonball drag (the same formula, r_cp × F) in the band of
    staregen's exponential table that holds the orbit, and the co-rotating air (zero wind)."""
    h0, rho0, H = atmosphere_band(np.linalg.norm(orbit.table5_initial_state()[:3]) - WGS84_A)
    atmosphere = bsk.atmosphere.ExponentialAtmosphere()
    atmosphere.ModelTag = "staregen_atmosphere"
    atmosphere.planetRadius, atmosphere.baseDensity, atmosphere.scaleHeight = float(WGS84_A + h0), float(rho0), float(H)
    atmosphere.planetPosInMsg.subscribeTo(planet.planetOutMsg)
    atmosphere.addSpacecraftToModel(sc.scStateOutMsg)
    wind = bsk.wind.ZeroWindModel()
    wind.ModelTag = "staregen_air"
    wind.setPlanetOmega_N(earth_rate_vector(*SCENARIO_EPOCH).tolist())
    wind.planetPosInMsg.subscribeTo(planet.planetOutMsg)
    wind.addSpacecraftToModel(sc.scStateOutMsg)
    drag = bsk.drag.DragDynamicEffector()
    drag.ModelTag = "staregen_drag"
    drag.coreParams.projectedArea = float(p.drag_area)
    drag.coreParams.dragCoeff = float(p.drag_coefficient)
    drag.coreParams.comOffset = [float(v) for v in p.drag_cp_offset]
    drag.atmoDensInMsg.subscribeTo(atmosphere.envOutMsgs[0])
    drag.windVelInMsg.subscribeTo(wind.envOutMsgs[0])
    sc.addDynamicEffector(drag)
    for model in (atmosphere, wind):
        sim.AddModelToTask(task, model, _PRIORITY["environment"])
    sim.AddModelToTask(task, drag, _PRIORITY["effectors"])
    return [atmosphere, wind, drag]


def _add_residual_dipole(bsk, sim, task: str, sc, planet, p) -> list:
    """staregen's residual dipole in its tilted-dipole field: Basilisk's centred-dipole field with the same
    IGRF-12 degree-1 coefficients on staregen's rotating Earth, and a torque-rod effector holding the dipole."""
    field = bsk.field.MagneticFieldCenteredDipole()
    field.ModelTag = "staregen_field"
    g11, h11, g10 = (float(v) * 1e-9 for v in IGRF2015_DIPOLE_NT)
    field.g10, field.g11, field.h11, field.planetRadius = g10, g11, h11, float(EARTH_RADIUS_DIPOLE)
    field.planetPosInMsg.subscribeTo(planet.planetOutMsg)
    field.addSpacecraftToModel(sc.scStateOutMsg)
    config = bsk.messaging.MTBArrayConfigMsgPayload()
    config.numMTB = 3
    config.GtMatrix_B = [1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0]
    config.maxMtbDipoles = [1e9, 1e9, 1e9]
    command = bsk.messaging.MTBCmdMsgPayload()
    command.mtbDipoleCmds = [float(v) for v in p.residual_dipole]
    config_msg = bsk.messaging.MTBArrayConfigMsg().write(config)
    command_msg = bsk.messaging.MTBCmdMsg().write(command)
    rods = bsk.mtb.MtbEffector()
    rods.ModelTag = "staregen_residual_dipole"
    rods.mtbParamsInMsg.subscribeTo(config_msg)
    rods.mtbCmdInMsg.subscribeTo(command_msg)
    rods.magInMsg.subscribeTo(field.envOutMsgs[0])
    sc.addDynamicEffector(rods)
    sim.AddModelToTask(task, field, _PRIORITY["environment"])
    sim.AddModelToTask(task, rods, _PRIORITY["effectors"])
    return [field, config_msg, command_msg, rods]


def _wheel_inertia(cfg: SimConfig) -> float:
    return cfg.spacecraft.momentum_limit / (WHEEL_MAX_RPM * 2.0 * np.pi / 60.0)


def _add_wheels(bsk, sim, task: str, sc, cfg: SimConfig, omega0: np.ndarray):
    factory = bsk.rwf.rwFactory()
    for i in range(3):
        axis = [0.0, 0.0, 0.0]
        axis[i] = 1.0
        factory.create("custom", axis, Omega=float(-omega0[i] * 60.0 / (2.0 * np.pi)), Omega_max=WHEEL_MAX_RPM,
                       maxMomentum=float(cfg.spacecraft.momentum_limit), u_max=float(cfg.spacecraft.torque_limit),
                       RWModel=bsk.messaging.BalancedWheels, useRWfriction=False, useMinTorque=False,
                       useMaxTorque=True)
    rw = bsk.rw.ReactionWheelStateEffector()
    rw.ModelTag = "staregen_wheels"
    factory.addToSpacecraft(rw.ModelTag, rw, sc)
    sim.AddModelToTask(task, rw, _PRIORITY["wheels"])
    return factory, rw


def staring_run(controller: Controller, lon: float, lat: float, cfg: SimConfig = SimConfig(), stream: int = 0) -> History:
    """Fly `controller` (stepped at the control period) staring at (lon, lat) in Basilisk; the
    signature of host.sim.simulator.simulate (cfg.external_torques and cfg.disturbances choose the
    disturbances, as in staregen's simulator). cfg.attitude_offset acts through the shared sensor read;
    cfg.extra_torque, a test input of staregen's simulator, is refused rather than silently dropped."""
    if cfg.extra_torque is not None:
        raise HostError("SimConfig.extra_torque (a test input of staregen's simulator) is not flown in Basilisk")
    bsk = basilisk()
    sub, n_ctrl = cfg.substeps, cfg.control_steps
    n = n_ctrl * sub
    env0 = environment_track(2, cfg.plant_step)
    x0 = initial_state(env0, lon, lat)
    L_bi0 = dcm_from_quat3(x0[0:4])
    omega0 = x0[4:7]

    sim = bsk.base.SimBaseClass()
    task = "staring"
    sim.CreateNewProcess("dynamics").addTask(sim.CreateNewTask(task, _nanos(cfg.plant_step)))
    sc = bsk.spacecraft.Spacecraft()
    sc.ModelTag = "staregen"
    js = _wheel_inertia(cfg)
    sc.hub.mHub = float(cfg.spacecraft.mass)
    sc.hub.r_BcB_B = [[0.0], [0.0], [0.0]]
    sc.hub.IHubPntBc_B = bsk.helpers.np2EigenMatrix3d(list((cfg.spacecraft.inertia + js * np.eye(3)).ravel()))
    state0 = orbit.table5_initial_state()
    sc.hub.r_CN_NInit = [[float(v)] for v in state0[:3]]
    sc.hub.v_CN_NInit = [[float(v)] for v in state0[3:]]
    sc.hub.sigma_BNInit = [[float(v)] for v in bsk.rbk.C2MRP(L_bi0)]
    sc.hub.omega_BN_BInit = [[float(v)] for v in omega0]
    sim.AddModelToTask(task, sc, _PRIORITY["spacecraft"])

    grav = bsk.grav.gravBodyFactory()
    earth = grav.createEarth()
    earth.isCentralBody = True
    earth.mu = MU_EARTH
    grav.addBodiesTo(sc)
    kept = _add_disturbances(bsk, sim, task, sc, earth, cfg)

    factory, rw = _add_wheels(bsk, sim, task, sc, cfg, omega0)
    drive = _StaringDrive(controller, lon, lat, cfg, stream, n)
    module = _flight_module(bsk, sim, task, drive, sc, wheels=True, tag="staregen_flight")
    rw.rwMotorCmdInMsg.subscribeTo(module.rwMotorTorqueOutMsg)
    states = sc.scStateOutMsg.recorder()
    speeds = rw.rwSpeedOutMsg.recorder()
    wheels = [rw.rwOutMsgs[i].recorder() for i in range(3)]   # u_current: the torque Basilisk applies
    for recorder in (states, speeds, *wheels):
        sim.AddModelToTask(task, recorder, _PRIORITY["recorders"])

    controller.reset()
    _execute(sim, n * cfg.plant_step)
    del kept   # Basilisk holds only pointers to these Python objects and messages: alive until the run ends
    applied = -np.stack([np.array(w.u_current, float) for w in wheels], axis=1)   # body torque = −u_s
    return _staring_history(states, speeds, applied, drive, js, n, lon, lat, cfg, stream, bsk)


def _staring_history(states, speeds, applied: np.ndarray, drive: _StaringDrive, js: float, n: int, lon, lat,
                     cfg: SimConfig, stream: int, bsk) -> History:
    """staregen's History of the recorded run: true errors from Basilisk's own orbit and attitude."""
    if len(states.times()) != n + 1:
        raise HostError(f"Basilisk recorded {len(states.times())} states, expected {n + 1}")
    t = np.arange(n + 1) * cfg.plant_step
    R, V = np.array(states.r_BN_N, float), np.array(states.v_BN_N, float)
    L_bi = np.array([bsk.rbk.MRP2C(s) for s in np.array(states.sigma_BN, float)])
    q_bi = quat_from_dcm(L_bi)
    w = np.array(states.omega_BN_B, float)
    h_w = js * (np.array(speeds.wheelSpeeds, float)[:, :3] + w)   # absolute momentum, axes = body axes
    jd, sec = add_seconds(*SCENARIO_EPOCH, t)
    env = EnvironmentTrack(t, jd, sec, np.hstack([R, V]))
    A_bd, omega_e, d = true_errors(env, q_bi, w, lon, lat)
    drive.rec_cmd[n], drive.mode[n] = drive.rec_cmd[n - 1], drive.mode[n - 1]
    applied = applied.copy()
    applied[n] = applied[n - 1]     # as staregen: no interval follows the last sample
    nan = np.full((n + 1, 3), np.nan)
    return History(t=t, A_bd=A_bd, omega_e=omega_e, omega_b=w, omega_d=d.omega_d, omegadot_d=d.omegadot_d,
                   q_bi=q_bi, h_w=h_w, torque_cmd=drive.rec_cmd, torque_applied=applied,
                   torque_ext=nan, A_bd_ctrl=nan.copy(), omega_e_ctrl=nan.copy(), mode=drive.mode.astype(str),
                   lon=float(lon), lat=float(lat), seed=cfg.seed, stream=stream)


# ----------------------------------------------------------------------------- paper 000's example

class _TanhDrive:
    """The tanh law stepped at the control instants (torque held), plus d(t) at every plant step."""

    def __init__(self, law, sc: "tanh_ex.Scenario", period: float, dt: float, n_sub: int, n: int):
        self.law, self.sc, self.dt, self.n_sub = law, sc, dt, n_sub
        self.disturbance = tanh_ex.plant(sc).disturbance
        self.out = None
        self.rows = np.empty(n + 1, dtype=object)

    def __call__(self, j: int, st) -> np.ndarray:
        if j % self.n_sub == 0:
            R_c = np.array(basilisk().rbk.MRP2C(np.array(st.sigma_BN, float)), float).T
            self.out = self.law.step(R_c, np.array(st.omega_BN_B, float), self.sc.R_t, self.sc.w_t,
                                     self.sc.wdot_t)[0]
        if j < len(self.rows):
            self.rows[j] = self.out
        torque = self.out["torque"].astype(float)
        return torque + np.asarray(self.disturbance(j * self.dt), float)


def tanh_run(law, period: float, duration: float, dt: float) -> dict:
    """Paper 000's example flown in Basilisk by `law` (host.control.package_controller.PackageTanhLaw):
    tanh_example's history (t, e, w_e, x2, u, varpi, status at every plant step, R_c_final)."""
    bsk = basilisk()
    sc = tanh_ex.paper_scenario()
    n_ctrl, n_sub = tanh_ex.step_count(duration, period), tanh_ex.step_count(period, dt)
    h = period / n_sub
    n = n_ctrl * n_sub
    sim = bsk.base.SimBaseClass()
    task = "tanh"
    sim.CreateNewProcess("dynamics").addTask(sim.CreateNewTask(task, _nanos(h)))
    body = bsk.spacecraft.Spacecraft()
    body.ModelTag = "paper000"
    body.hub.mHub = 100.0   # kg; the example's translation is not simulated (no gravity), any mass will do
    body.hub.r_BcB_B = [[0.0], [0.0], [0.0]]
    body.hub.IHubPntBc_B = bsk.helpers.np2EigenMatrix3d([x for row in sc.plant_inertia for x in row])
    body.hub.sigma_BNInit = [[float(v)] for v in bsk.rbk.C2MRP(np.array(sc.R_c0, float).T)]
    body.hub.omega_BN_BInit = [[float(v)] for v in sc.w_c0]
    sim.AddModelToTask(task, body, _PRIORITY["spacecraft"])
    ext = bsk.ext.ExtForceTorque()
    ext.ModelTag = "paper000_torque"
    body.addDynamicEffector(ext)
    sim.AddModelToTask(task, ext, _PRIORITY["wheels"])
    law.reset()
    drive = _TanhDrive(law, sc, period, h, n_sub, n)
    module = _flight_module(bsk, sim, task, drive, body, wheels=False, tag="staregen_tanh")
    ext.cmdTorqueInMsg.subscribeTo(module.cmdTorqueOutMsg)
    states = body.scStateOutMsg.recorder()
    sim.AddModelToTask(task, states, _PRIORITY["recorders"])
    _execute(sim, n * h)
    return _tanh_history(sc, states, drive, n, h, bsk)


def _tanh_history(sc, states, drive: _TanhDrive, n: int, h: float, bsk) -> dict:
    if len(states.times()) != n + 1:
        raise HostError(f"Basilisk recorded {len(states.times())} states, expected {n + 1}")
    c = tanh_ex.compile_constants(sc.params)
    hist = tanh_ex.History(n + 1)
    w_all = np.array(states.omega_BN_B, float)
    R_all = [np.array(bsk.rbk.MRP2C(s), float).T for s in np.array(states.sigma_BN, float)]
    for j in range(n + 1):
        y = [float(x) for x in R_all[j].ravel()] + [float(x) for x in w_all[j]]
        e, w_e = tanh_ex.true_errors(c, sc, y)
        row = drive.rows[j]
        out = SimpleNamespace(torque=row["torque"].astype(float), x1=e, x2=row["x2"].astype(float), w_e=w_e,
                              status=int(row["status"]))
        hist.add(j * h, out, row["varpi"].astype(float), e, w_e)
    return {**hist.as_dict(), "R_c_final": R_all[-1]}
