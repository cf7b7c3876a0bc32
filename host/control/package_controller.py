"""A flight package's units as host controllers: the package's own C, linked through its public API
(tools.package_lib), stepped with the ICD's records. Any simulator flies them: staregen's own and
Basilisk (host.sim.basilisk), so a cross-check compares two plants flying the same object code.

  PackageController   the Fig. 2 controller, `<name>_step` (network + PID fallback; a package
                      generated with `--pid-only` flies its PID on every step);
  PackageTanhLaw      paper 000's tanh law, `<name>_tanh_step`, on its example's records.
"""
from __future__ import annotations

import numpy as np

from codegen.units.controller import emit as controller_records
from codegen.units.tanh import emit as tanh_records
from host.control.controllers import ControlOutput, Measurement
from host.control.generated_controller import control_output, pack_input
from tools.package_lib import FlightPackage, Records, load_package

CONTROLLER_RECORDS = Records(controller_records.INPUT_DTYPE, controller_records.OUTPUT_DTYPE,
                             controller_records.STATE_DTYPE)
TANH_RECORDS = Records(tanh_records.INPUT_DTYPE, tanh_records.OUTPUT_DTYPE, tanh_records.STATE_DTYPE)


_loaded: dict[tuple[str, bytes | None], FlightPackage] = {}


def loaded_package(folder: str, key: bytes | None = None) -> FlightPackage:
    """The package in `folder`, checked (its signature under `key`, when given), built and self-tested
    once per process (worker processes of a many-target run each load it once)."""
    if (folder, key) not in _loaded:
        _loaded[(folder, key)] = load_package(folder, key)
    return _loaded[(folder, key)]


def make_package_controller(folder: str, name: str = "fig2", key: bytes | None = None) -> "PackageController":
    """A picklable factory (functools.partial of it) for host.sim.simulator.simulate_targets."""
    return PackageController(loaded_package(folder, key), name)


def pid_only(package: FlightPackage) -> bool:
    """Whether the package's controller was generated with an empty envelope (PID on every step)."""
    identity = package.manifest.get("units", {}).get("controller", {}).get("identity", "")
    return isinstance(identity, str) and identity.endswith(", PID only")


class PackageController:
    """`<name>_init` at reset, `<name>_step` once per control period (the package's controller)."""

    def __init__(self, package: FlightPackage, name: str = "fig2"):
        self.name = name
        self.entry = package.entry("controller", CONTROLLER_RECORDS)

    def reset(self) -> None:
        self.entry.init()

    def step(self, m: Measurement) -> ControlOutput:
        return control_output(self.entry.step(pack_input(m)))


class PackageTanhLaw:
    """`<name>_tanh_init` / `<name>_tanh_step` on paper 000's records: (R_c, ω_c) of the plant and the
    target (R_t, ω_t, ω̇_t); returns the output record (torque, x1, x2, varpi, status)."""

    name = "tanh"

    def __init__(self, package: FlightPackage):
        self.entry = package.entry("tanh", TANH_RECORDS)

    def reset(self) -> None:
        self.entry.init()

    def step(self, R_c, w_c, R_t, w_t, wdot_t) -> np.ndarray:
        rec = np.zeros(1, dtype=TANH_RECORDS.input)
        with np.errstate(over="ignore"):   # float32 rounding, as on board
            rec["R_c"], rec["w_c"] = np.ravel(R_c), w_c
            rec["R_t"], rec["w_t"], rec["wdot_t"] = np.ravel(R_t), w_t, wdot_t
        return self.entry.step(rec)
