"""The x86 SIL guard on the SSE control register: a batch refuses to run when something in the
process set flush-to-zero, denormals-are-zero or a directed rounding mode in MXCSR (the golden
model assumes IEEE defaults, so results on subnormals / rounding would silently differ)."""
import contextlib
import re

import numpy as np
import pytest

from codegen import artifact as art
from codegen.units.network import golden
from codegen.units.controller.emit import INPUT_DTYPE, STATE_DTYPE
from firmware import x86
from firmware.errors import FirmwareError
from firmware.x86_controller import X86Controller
from host import tanh_example as ex
from host.nn_controller import flight_config, load_artifact
from host.tanh_sil import X86Tanh

CONTROL = 0xFFC0  # MXCSR control bits; bits 0-5 are sticky exception flags that float code sets


pytestmark = pytest.mark.usefixtures("private_cache")  # conftest: a build cache of its own


@pytest.fixture(scope="module")
def artifact():
    return art.random_artifact((5, 17, 2), seed=4)


@pytest.fixture(scope="module")
def net(artifact):
    return x86.network_library(artifact)


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


def test_tanh_and_controller_batches_are_guarded():
    tanh = X86Tanh(ex.paper_parameters())
    ctrl = X86Controller(load_artifact(None), flight_config())
    calls = [
        (tanh.build, lambda: tanh.step(np.zeros((1, 3), np.float32), np.zeros((1, 27), np.float32))),
        (tanh.build, lambda: tanh.sequence(np.zeros((1, 27), np.float32))),
        (ctrl.build, lambda: ctrl.run_records(np.zeros(1, STATE_DTYPE), np.zeros(1, INPUT_DTYPE))),
        (ctrl.build, lambda: ctrl.run_sequence(np.zeros(1, INPUT_DTYPE))),
    ]
    for build, call in calls:
        with mxcsr(build, x86.MXCSR_FTZ), pytest.raises(FirmwareError, match="FTZ"):
            call()
        call()
