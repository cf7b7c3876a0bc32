"""STM32F417 build, harness and the ARM bit-exact gate; `staregen cycles` end to end."""
import json
import os
import subprocess
import sys

import numpy as np
import pytest

from codegen import artifact as art
from codegen import bitcompare
from codegen.unit import Batch
from codegen.units.network import golden, vectors
from codegen.units.network.unit import NetworkUnit
from firmware import arm
from firmware.errors import FirmwareError
from host.cli import main
from tools.errors import ToolError
from tools.m4.elf import Image
from tools.m4.harness import Harness
from tools.m4.machine import SCB_CPACR, Machine
from tools.runners import arm_build, runner
from unicorn import arm_const as R


pytestmark = pytest.mark.usefixtures("private_cache")  # conftest: a build cache of its own


@pytest.fixture(scope="module")
def net12():
    return art.random_artifact((12, 40, 3), seed=1)


def evaluate(unit, target, x):
    rec = np.zeros(x.shape[0], dtype=unit.input_dtype)
    rec["x"] = x
    return np.ascontiguousarray(runner(unit, target).records(Batch(None, rec))[0]["y"])


def _three_way(a, n, seed):
    unit = NetworkUnit(a)
    vs = vectors.gate_vectors(a.envelope, n, seed)
    y_gold = golden.network_eval(a, vs.x)
    return (bitcompare.compare(y_gold, evaluate(unit, "x86", vs.x)),
            bitcompare.compare(y_gold, evaluate(unit, "arm", vs.x)))


def test_three_way_gate_1e5_vectors(net12):
    c_x86, c_arm = _three_way(net12, 100_000, seed=0)
    assert c_x86.ok and c_arm.ok, (c_x86.report("golden", "x86"), c_arm.report("golden", "arm"))


def test_three_way_gate_second_shape():
    c_x86, c_arm = _three_way(art.random_artifact((7, 10, 2), seed=5), 20_000, seed=3)
    assert c_x86.ok and c_arm.ok


def test_build_links_no_libm_no_hal_and_no_newlib(net12):
    build = arm_build(NetworkUnit(net12))
    arm.check_symbols(build.elf)
    assert not build.newlib
    assert "libm.a" not in build.map.read_text()
    symbols = set(Image(build.elf).by_name)
    # the step: network_eval and the MLP loop it tail-calls; tanh inline (no sg_tanhf linked)
    assert {"network_eval", "network_hidden"} <= symbols and "sg_tanhf" not in symbols


def _one_input_net(net_c: str) -> tuple[dict, str]:
    """Sources of a 1-in 1-out `net_eval` with the given net.c, and the network adapter for it."""
    src = {"net.c": net_c,
           "net.h": "#define NET_N_IN 1\n#define NET_N_OUT 1\nvoid net_eval(const float *x, float *y);\n"}
    adapter = arm.render_adapter("records", entry="net", header="net.h", step="net_eval", init="",
                                 layout_checks=["NET_N_IN == 1"], input_words=1, output_words=1, state_words=0)
    return src, adapter


def test_forbidden_symbol_is_detected(tmp_path):
    src, adapter = _one_input_net("float expf(float x);\n__attribute__((noinline)) float expf(float x) { return x; }\n"
                                  "void net_eval(const float *x, float *y) { y[0] = expf(x[0]); }\n")
    with pytest.raises(FirmwareError, match="forbidden library symbols linked: expf"):
        arm.build(src, adapter)


def test_libm_call_does_not_link():
    src, adapter = _one_input_net("float tanhf(float x);\n"
                                  "void net_eval(const float *x, float *y) { y[0] = tanhf(x[0]); }\n")
    with pytest.raises(FirmwareError, match="undefined reference to `tanhf'"):
        arm.build(src, adapter)
    # Only a peer build (third-party C measured for comparison) may link libm and newlib.
    peer = arm.build(src, adapter, peer=True)
    assert peer.newlib and "tanhf" in Image(peer.elf).by_name


STATEFUL_H = """#include <stdint.h>
typedef struct { float acc; uint32_t n; } ctr_state;
typedef struct { float u; } ctr_input;
typedef struct { float y; float n; float calls; } ctr_output;
void ctr_init(ctr_state *s);
void ctr_step(ctr_state *s, const ctr_input *in, ctr_output *out);
"""
STATEFUL_C = """#include "ctr.h"
static float gain = 2.0f;       /* .data: copied from flash by startup */
static uint32_t calls;          /* .bss: zeroed by startup */
void ctr_init(ctr_state *s) { s->acc = 0.0f; s->n = 0u; }
void ctr_step(ctr_state *s, const ctr_input *in, ctr_output *out)
{
    s->acc = s->acc + gain * in->u;
    s->n = s->n + 1u;
    calls = calls + 1u;
    out->y = s->acc;
    out->n = (float)s->n;
    out->calls = (float)calls;
}
"""


def test_stateful_adapter_startup_and_reset():
    adapter = arm.render_adapter("sequence", entry="ctr", header="ctr.h", step="ctr_step", init="ctr_init",
                                 layout_checks=["sizeof(ctr_state) == 8u", "offsetof(ctr_output, calls) == 8u"],
                                 input_words=1, output_words=3, state_words=2)
    build = arm.build({"ctr.h": STATEFUL_H, "ctr.c": STATEFUL_C}, adapter)
    image = Image(build.elf)
    machine = Machine(image)
    machine.write(image.symbol("_sbss"), b"\xff" * 64)  # garbage that startup must clear
    h = Harness(image, machine=machine)
    assert int.from_bytes(machine.read(SCB_CPACR, 4), "little") == 0xF << 20
    assert machine.uc.reg_read(R.UC_ARM_REG_FPSCR) == 0
    u = np.array([[1.0], [0.5], [0.25]], dtype=np.float32)
    run = lambda: h.run(u.view(np.uint8)).view(np.float32)
    first = run()
    np.testing.assert_array_equal(first, [[2.0, 1, 1], [3.0, 2, 2], [3.5, 3, 3]])
    h.reset()  # state back to ctr_init; the .bss call counter keeps counting
    np.testing.assert_array_equal(run(), [[2.0, 1, 4], [3.0, 2, 5], [3.5, 3, 6]])


def test_a_layout_check_that_fails_stops_the_build():
    """The adapters carry the unit's sizeof/offsetof checks: a dtype that drifted from its C struct
    cannot be built (negative array size at compile time)."""
    adapter = arm.render_adapter("sequence", entry="ctr", header="ctr.h", step="ctr_step", init="ctr_init",
                                 layout_checks=["sizeof(ctr_state) == 12u"], input_words=1, output_words=3,
                                 state_words=2)
    with pytest.raises(FirmwareError, match="adapter.c does not compile"):
        arm.build({"ctr.h": STATEFUL_H, "ctr.c": STATEFUL_C}, adapter)


def test_batches_larger_than_the_arena(net12):
    unit = NetworkUnit(net12)
    n = Harness(arm_build(unit).elf).capacity * 2 + 7
    x = vectors.gate_vectors(net12.envelope, n, 9).x
    assert bitcompare.compare(golden.network_eval(net12, x), evaluate(unit, "arm", x)).ok


def test_unknown_adapter_and_non_harness_elf(tmp_path):
    with pytest.raises(FirmwareError, match="no harness adapter 'pid'"):
        arm.render_adapter("pid")
    elf = arm.bench_build(tmp_path)
    with pytest.raises(ToolError, match="symbol 'harness_run' is not in bench.elf"):
        Harness(elf)


def test_cycles_cli_json_report(net12, tmp_path, capsys):
    path = tmp_path / "a.json"
    net12.save(path)
    out_json, out_md = tmp_path / "c.json", tmp_path / "c.md"
    rc = main(["cycles", "--artifact", str(path), "--mode", "all", "--per-class", "20",
               "--json", str(out_json), "--md", str(out_md)])
    assert rc == 0
    report = json.loads(out_json.read_text())
    assert list(report) == ["entries"] and list(report["entries"]) == ["network"]
    entry = report["entries"]["network"]
    assert {"cycles", "by_class", "flash_bytes", "ram_bytes", "stack_bytes", "functions", "budgets"} <= set(entry)
    for mode in ("ideal", "art", "pessimistic"):
        s = entry["cycles"][mode]
        assert 0 < s["min"] <= s["median"] <= s["max"]
    assert entry["cycles"]["ideal"]["max"] < entry["cycles"]["art"]["max"] < entry["cycles"]["pessimistic"]["max"]
    funcs = entry["functions"]
    assert funcs["network_hidden"]["calls"]["max"] == 1 and "sg_tanhf" not in funcs
    assert funcs["network_eval"]["inclusive"]["ideal"] == entry["cycles"]["ideal"]
    # RAM: the tables copied to CCM at start-up, at least the 40 x 16 weights and the signed tanh
    # table's 2 x 128 rows of 8 floats (4 bytes each); the JSON carries the static bound beside
    # the samples
    assert 0 < entry["flash_bytes"] <= 16 * 1024 and 4 * (40 * 16 + 2 * 128 * 8) <= entry["ram_bytes"] <= 16 * 1024
    for mode in ("ideal", "art"):
        assert entry["bound"]["strict"][mode] >= entry["cycles"][mode]["max"]
        assert entry["bound"]["lenient"][mode] >= entry["cycles_lenient"][mode]["max"]
    assert 0 < entry["stack_bytes"] <= 512
    assert "| ideal |" in out_md.read_text() and "µs" in capsys.readouterr().out


def test_missing_toolchain_is_one_line_error(net12, tmp_path):
    path = tmp_path / "a.json"
    net12.save(path)
    env = dict(os.environ, PATH=str(tmp_path / "empty"))
    res = subprocess.run([sys.executable, "-c", "import sys; from host.cli import main; sys.exit(main())",
                          "cycles", "--artifact", str(path)],
                         capture_output=True, text=True, env=env, timeout=120)
    assert res.returncode == 2
    assert res.stderr.strip() == ("staregen cycles: error: ARM toolchain: 'arm-none-eabi-gcc' not found "
                                  "on PATH (install gcc-arm-none-eabi and libnewlib-arm-none-eabi, see tools/setup.sh)")
