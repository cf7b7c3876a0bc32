"""The generated controller flown in the simulator: SIL (x86 build through cffi) and PIL (the
STM32F417 ELF in the Cortex-M4 emulator, with the cycles of every step).

Each control period the Measurement is packed into the C input struct exactly as a flight computer
would fill it: float32 SI values, UTC as (days since 2000-01-01, milliseconds of day). Registered
controllers:
  nn-c    generated controller on x86 (network inside the envelope, PID fallback);
  pid-c   the same generated controller generated with ControllerConfig.pid_only (its envelope
          emitted empty), so every step flies its PID branch: the flight PID code, not a separate
          entry point (the network is still linked, never called);
  nn-arm  generated controller on the emulated Cortex-M4; ControlOutput.info["cycles"] holds the
          step's cycle count (ideal memory).
"""
from __future__ import annotations

import dataclasses

import numpy as np

from codegen import controller_spec as cs
from codegen.artifact import Artifact
from codegen.controller_emit import DEFAULT_NAME, INPUT_DTYPE, OUTPUT_DTYPE, controller_sources, to_bam
from host.controllers import ControlOutput, Measurement
from host.nn_controller import flight_config, load_artifact
from host.timebase import normalise_time


def pack_input(m: Measurement) -> np.ndarray:
    """One INPUT_DTYPE record from a Measurement (float32 rounding happens here, as on board)."""
    jd, sec = normalise_time(int(m.jd_days), float(m.sec_of_day))
    rec = np.zeros(1, dtype=INPUT_DTYPE)
    rec["A_bo"], rec["omega_b"] = m.A_bo, m.omega_b
    rec["R_s"], rec["V_s"] = m.R_s, m.V_s
    rec["lon"], rec["lat"] = to_bam(m.lon), to_bam(m.lat)
    rec["utc_day"] = int(jd) - cs.J2000_JDN
    rec["utc_ms"] = int(round(float(sec) * 1000.0))
    return rec


def control_output(out: np.ndarray, **extra) -> ControlOutput:
    status = int(out["status"][0])
    mode = "pid" if status & cs.STATUS_PID else "nn"
    info = {"A_bd": out["A_bd"][0].astype(float), "omega_e": out["omega_e"][0].astype(float),
            "status": status, **extra}
    return ControlOutput(torque=out["torque"][0].astype(float), mode=mode, info=info)


class Trace:
    """Every input record and output record of a run, for the step-by-step golden comparison."""

    def __init__(self):
        self.inputs: list[np.ndarray] = []
        self.outputs: list[np.ndarray] = []
        self.cycles: list[int] = []

    def add(self, rec: np.ndarray, out: np.ndarray, cycles: int | None = None) -> None:
        self.inputs.append(rec)
        self.outputs.append(out)
        if cycles is not None:
            self.cycles.append(cycles)

    def arrays(self) -> tuple[np.ndarray, np.ndarray]:
        """(inputs (T,), outputs (T,)) structured arrays."""
        return np.concatenate(self.inputs), np.concatenate(self.outputs)


class SilController:
    """The generated controller on x86, one cffi call per control period."""

    def __init__(self, artifact: Artifact, cfg: cs.ControllerConfig, name: str = "nn-c"):
        from firmware.x86_controller import X86Controller

        self.name = name
        self.c = X86Controller(artifact, cfg)
        self.trace = Trace()

    def reset(self) -> None:
        self.c.reset()
        self.trace = Trace()

    def step(self, m: Measurement) -> ControlOutput:
        rec = pack_input(m)
        out = self.c.run_sequence(rec)
        self.trace.add(rec, out)
        return control_output(out)


class PilController:
    """The generated controller's ARM ELF in the emulator, one harness call per control period."""

    name = "nn-arm"

    def __init__(self, artifact: Artifact, cfg: cs.ControllerConfig):
        from tools.m4.elf import Image
        from tools.m4.harness import Harness
        from tools.m4.profile import Profiler

        image = Image(controller_arm_build(artifact, cfg).elf)
        self.profiler = Profiler(image, f"{DEFAULT_NAME}_step", memory_modes=False)
        self.harness = Harness(image, machine=self.profiler.machine)
        self.trace = Trace()

    def reset(self) -> None:
        self.harness.reset(runner=self.profiler.run)
        self.trace = Trace()

    def step(self, m: Measurement) -> ControlOutput:
        rec = pack_input(m)
        raw = self.harness.run(rec.view(np.uint8).reshape(1, -1), runner=self.profiler.run)
        cycles = int(self.profiler.evaluations[-1].total[0])   # ideal memory
        self.profiler.evaluations.clear()
        out = raw.view(OUTPUT_DTYPE).reshape(1).copy()
        self.trace.add(rec, out, cycles)
        return control_output(out, cycles=cycles)


def controller_arm_build(artifact: Artifact, cfg: cs.ControllerConfig, adapter: str = "stateful",
                         name: str = DEFAULT_NAME):
    """The controller ELF with the `stateful` (state in the adapter) or `state_in_record` adapter."""
    from firmware import arm

    text = arm.render_adapter(adapter, entry=name, header=f"{name}.h", state_t=f"{name}_state_t",
                              input_t=f"{name}_input_t", output_t=f"{name}_output_t")
    return arm.build(controller_sources(artifact, cfg, name), text)


def make_sil_controller(*, torque_limit: float, control_period: float, artifact: str | None = None):
    return SilController(load_artifact(artifact), flight_config(torque_limit, control_period))


def make_sil_pid_controller(*, torque_limit: float, control_period: float, artifact: str | None = None):
    cfg = dataclasses.replace(flight_config(torque_limit, control_period), pid_only=True)
    return SilController(load_artifact(artifact), cfg, name="pid-c")


def make_pil_controller(*, torque_limit: float, control_period: float, artifact: str | None = None):
    return PilController(load_artifact(artifact), flight_config(torque_limit, control_period))
