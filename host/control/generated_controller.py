"""The generated flight controller flown in the staring simulator: SIL (x86) and PIL (ARM emulator).

Each control period the Measurement is packed into the unit's input record exactly as a flight
computer would fill it (float32 SI values, UTC as days since 2000-01-01 and milliseconds of day,
target as binary angles) and stepped by tools.inloop. The golden twin is off by default (it would
double the cost of a campaign); the tests replay `loop.trace()` through the golden model, and
`golden_twin=True` compares every step as it happens. Registered controllers (host.control.controllers):
  nn-c    generated controller on x86 (network inside the envelope, PID fallback);
  pid-c   the same controller generated with ControllerConfig.pid_only (its envelope emitted
          empty), so every step flies its PID branch: the flight PID code, not a separate entry;
  nn-arm  generated controller on the emulated Cortex-M4; ControlOutput.info["cycles"] holds the
          step's cycles (ideal memory).
"""
from __future__ import annotations

import dataclasses

import numpy as np

from codegen.unit import Batch
from codegen.units.controller import spec as cs
from codegen.units.controller.emit import INPUT_DTYPE, to_bam
from codegen.units.controller.unit import ControllerUnit
from host.control.batch import BatchLayout, BatchMeasurement, BatchOutput
from host.control.controllers import ControlOutput, Measurement
from host.control.nn_controller import flight_config, load_artifact
from host.core.timebase import normalise_time
from tools.inloop import InTheLoop
from tools.runners import runner


def pack_input(m: Measurement | BatchMeasurement) -> np.ndarray:
    """Input records from a Measurement (one record) or a BatchMeasurement (one per row, one clock and
    one GPS fix for all); the float32 rounding happens here, as on board."""
    jd, sec = normalise_time(int(m.jd_days), float(m.sec_of_day))
    rec = np.zeros(m.rows if isinstance(m, BatchMeasurement) else 1, dtype=INPUT_DTYPE)
    rec["A_bo"], rec["omega_b"] = m.A_bo, m.omega_b
    rec["R_s"], rec["V_s"] = m.R_s, m.V_s
    rec["lon"], rec["lat"] = to_bam(m.lon), to_bam(m.lat)
    rec["utc_day"] = int(jd) - cs.J2000_JDN
    rec["utc_ms"] = int(round(float(sec) * 1000.0))
    return rec


def control_output(out: np.ndarray, **extra) -> ControlOutput:
    status = int(out["status"][0])
    info = {"A_bd": out["A_bd"][0].astype(float), "omega_e": out["omega_e"][0].astype(float),
            "status": status, **extra}
    return ControlOutput(torque=out["torque"][0].astype(float), mode="pid" if status & cs.STATUS_PID else "nn",
                         info=info)


class GeneratedController:
    """The controller unit in the loop on one target (x86: SIL, arm: PIL with cycles)."""

    def __init__(self, unit: ControllerUnit, target: str, name: str, golden_twin: bool = False):
        self.name, self.target = name, target
        self.loop = InTheLoop(unit, target, golden_twin=golden_twin)

    def reset(self) -> None:
        self.loop.reset()

    def step(self, m: Measurement) -> ControlOutput:
        out = self.loop.step(pack_input(m))
        extra = {"cycles": self.loop.cycles[-1]} if self.target == "arm" else {}
        return control_output(out, **extra)


class GeneratedBatch:
    """The controller unit on x86 for every row: one call of its record runner per control step, each
    row's state carried from the previous call (SIL, batched)."""

    variants = 1

    def __init__(self, unit: ControllerUnit, name: str):
        self.name, self.unit = name, unit
        self.run = runner(unit, "x86")

    def reset(self, layout: BatchLayout) -> None:
        self.state = self.unit.init_state(layout.rows)

    def step(self, m: BatchMeasurement) -> BatchOutput:
        out, self.state = self.run.records(Batch(self.state, pack_input(m)))
        return BatchOutput(torque=out["torque"].astype(float), saturated=(out["status"] & cs.STATUS_SATURATED) != 0)


def _unit(artifact: str | None, torque_limit: float, control_period: float, pid_only: bool = False):
    cfg = flight_config(torque_limit, control_period)
    return ControllerUnit(load_artifact(artifact), dataclasses.replace(cfg, pid_only=pid_only))


def make_sil_controller(*, torque_limit: float, control_period: float, artifact: str | None = None):
    return GeneratedController(_unit(artifact, torque_limit, control_period), "x86", "nn-c")


def make_sil_pid_controller(*, torque_limit: float, control_period: float, artifact: str | None = None):
    return GeneratedController(_unit(artifact, torque_limit, control_period, pid_only=True), "x86", "pid-c")


def make_pil_controller(*, torque_limit: float, control_period: float, artifact: str | None = None):
    return GeneratedController(_unit(artifact, torque_limit, control_period), "arm", "nn-arm")


def make_sil_batch(*, torque_limit: float, control_period: float, artifact: str | None = None):
    return GeneratedBatch(_unit(artifact, torque_limit, control_period), "nn-c")


def make_sil_pid_batch(*, torque_limit: float, control_period: float, artifact: str | None = None):
    return GeneratedBatch(_unit(artifact, torque_limit, control_period, pid_only=True), "pid-c")
