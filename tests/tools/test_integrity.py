"""Issue 14, integrity of constants: the controller's init and integrity_check compute the CRC-32 of
the network's constant tables on the target; fault injection in the STM32F417 image (emulator):
every one of 1,000 random single-bit flips of the weight tables in flash is detected, the intact
image is not flagged, and a flagged state flies the PID with STATUS_INTEGRITY."""
from __future__ import annotations

import numpy as np

from codegen.artifact import random_artifact
from codegen.units.controller import spec as cs
from host.sim.scenarios import configure_unit
from tools.m4.elf import Image
from tools.m4.machine import Machine
from tools.runners import arm_build, runner

FLIPS = 1_000


def test_every_single_bit_flip_of_the_weights_is_detected():
    unit = configure_unit("controller", artifact=random_artifact((12, 40, 3), seed=1), name="stare")
    image = Image(arm_build(unit, "sequence").elf)
    machine = Machine(image)
    machine.boot()
    table = image.symbol("stare_nn_neurons")
    size = 40 * (1 + 12 + 3) * 4
    state = image.symbol("_sarena")
    machine.call("stare_init", (state,))                    # init runs stare_integrity_check
    assert int.from_bytes(machine.read(state + 20, 4), "little") == 0          # intact: no fault
    rng = np.random.default_rng(0)
    detected = 0
    for byte, bit in zip(rng.integers(0, size, FLIPS), rng.integers(0, 8, FLIPS)):
        addr = table + int(byte)
        good = machine.read(addr, 1)
        machine.write(addr, bytes([good[0] ^ (1 << int(bit))]))
        machine.call("stare_init", (state,), max_insns=5_000_000)
        fault = int.from_bytes(machine.read(state + 20, 4), "little")        # state.fault (after integral, mode, clean)
        detected += fault != 0
        machine.write(addr, good)
    assert detected == FLIPS
    machine.call("stare_init", (state,))
    assert int.from_bytes(machine.read(state + 20, 4), "little") == 0


def test_a_faulted_state_flies_the_pid_with_the_integrity_bit():
    unit = configure_unit("controller", artifact=random_artifact((12, 40, 3), seed=1))
    batch = unit.gate_classes(400, seed=2)["inside"]
    state = unit.init_state(batch.input.shape[0])
    state["fault"] = 1
    out, after = unit.golden(state, batch.input)
    assert np.all(out["status"] & cs.STATUS_INTEGRITY) and np.all(out["status"] & cs.STATUS_PID)
    assert np.all(after["fault"] == 1)
    c_out, _ = runner(unit, "x86").records(batch._replace(state=state))
    assert np.array_equal(out.view(np.uint8), c_out.view(np.uint8))
    clean, _ = unit.golden(unit.init_state(batch.input.shape[0]), batch.input)
    assert not np.any(clean["status"] & cs.STATUS_INTEGRITY)
