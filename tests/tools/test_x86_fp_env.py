"""The x86 SIL guard on the SSE control register: a batch refuses to run when something in the
process set flush-to-zero, denormals-are-zero or a directed rounding mode in MXCSR (the golden
model assumes IEEE defaults, so results on subnormals / rounding would silently differ)."""
import contextlib
import re

import numpy as np
import pytest

from codegen import artifact as art
from codegen.unit import Batch
from codegen.units.network import golden
from codegen.units.network.unit import NetworkUnit
from firmware import x86
from firmware.errors import FirmwareError
from host.sim import tanh_example as ex
from host.control.nn_controller import load_artifact
from host.sim.scenarios import configure_unit
from tools.runners import X86Runner

CONTROL = 0xFFC0  # MXCSR control bits; bits 0-5 are sticky exception flags that float code sets


pytestmark = pytest.mark.usefixtures("private_cache")  # conftest: a build cache of its own


@pytest.fixture(scope="module")
def artifact():
    return art.random_artifact((5, 17, 2), seed=4)


class Net:
    """The network unit's x86 runner on float32 rows."""

    def __init__(self, artifact):
        self.run = X86Runner(NetworkUnit(artifact))
        self.build = self.run.build

    def eval(self, x):
        rec = np.zeros(x.shape[0], dtype=self.run.unit.input_dtype)
        rec["x"] = x
        return np.ascontiguousarray(self.run.records(Batch(None, rec))[0]["y"])


@pytest.fixture(scope="module")
def net(artifact):
    return Net(artifact)


@contextlib.contextmanager
def mxcsr(build, bits):
    """Set extra MXCSR bits in this thread for the block; the original value is always restored."""
    saved = build.lib.sg_host_mxcsr()
    try:
        build.lib.sg_host_set_mxcsr(saved | bits)
        yield
    finally:
        build.lib.sg_host_set_mxcsr(saved)
    assert build.lib.sg_host_mxcsr() & CONTROL == saved & CONTROL


def test_default_environment_passes_and_matches_golden(net, artifact):
    assert net.build.lib.sg_host_mxcsr() & (x86.MXCSR_FTZ | x86.MXCSR_DAZ | x86.MXCSR_RC) == 0
    net.build.check_fp_environment()
    x = np.random.default_rng(0).standard_normal((64, artifact.n_in)).astype(np.float32)
    assert np.array_equal(net.eval(x).view(np.uint32), golden.network_eval(artifact, x).view(np.uint32))


@pytest.mark.parametrize("bits, named", [
    (x86.MXCSR_FTZ, "flush-to-zero (FTZ)"),
    (x86.MXCSR_DAZ, "denormals-are-zero (DAZ)"),
    (1 << 13, "rounding mode round-down"),
    (2 << 13, "rounding mode round-up"),
    (x86.MXCSR_RC, "rounding mode round-toward-zero"),
])
def test_network_batch_refuses_a_changed_mxcsr(net, artifact, bits, named):
    x = np.zeros((3, artifact.n_in), dtype=np.float32)
    with mxcsr(net.build, bits), pytest.raises(FirmwareError) as info:
        net.eval(x)
    message = str(info.value)
    assert named in message and "MXCSR 0x" in message and "\n" not in message
    net.eval(x)  # restored: runs again


def test_every_set_bit_is_named(net):
    with mxcsr(net.build, x86.MXCSR_FTZ | x86.MXCSR_DAZ), pytest.raises(FirmwareError) as info:
        net.build.check_fp_environment()
    reported = int(re.search(r"MXCSR 0x([0-9a-f]+) ", str(info.value)).group(1), 16)
    assert reported & (x86.MXCSR_FTZ | x86.MXCSR_DAZ) == x86.MXCSR_FTZ | x86.MXCSR_DAZ
    assert "(FTZ)" in str(info.value) and "(DAZ)" in str(info.value)


@pytest.mark.parametrize("kind", ["controller", "tanh"])
def test_stateful_units_records_and_sequences_are_guarded(kind):
    inputs = {"artifact": load_artifact(None)} if kind == "controller" else {"params": ex.paper_parameters()}
    run = X86Runner(configure_unit(kind, **inputs))
    unit = run.unit
    calls = [lambda: run.records(Batch(unit.init_state(1), np.zeros(1, unit.input_dtype))),
             lambda: run.sequence(np.zeros(1, unit.input_dtype))]
    for call in calls:
        with mxcsr(run.build, x86.MXCSR_FTZ), pytest.raises(FirmwareError, match="FTZ"):
            call()
        call()
