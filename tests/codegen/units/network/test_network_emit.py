"""C emitter: deterministic output, exact constants and layout, C99/flags clean on both targets,
no libm / malloc / mutable globals in the objects, and the M4 inner loop without spills."""
import re
import shutil
import subprocess

import numpy as np
import pytest

import host.cli as cli
from codegen import GENERATOR_VERSION
from codegen import artifact as art
from codegen.cgen import c_float, write_sources
from codegen.errors import CodegenError
from codegen.units.network import emit
from codegen.units.network.unit import NetworkUnit
from firmware import flags, x86
from firmware.errors import FirmwareError
from tools.cycles import profile_entry
from tools.runners import LAYOUT_FILE, X86Runner, arm_build, pack

LIBM = {"tanhf", "tanh", "expf", "exp", "logf", "log", "sinf", "sin", "cosf", "cos", "atan2f", "atan2",
        "asinf", "asin", "sqrtf", "sqrt", "powf", "pow", "fabsf", "floorf", "expm1f", "__expf_finite"}
ALLOC = {"malloc", "calloc", "realloc", "free", "aligned_alloc", "memcpy", "memset"}
STAGES = ("normalise", "mlp", "denormalise", "eval")


@pytest.fixture(scope="module")
def artifact():
    return art.random_artifact((12, 40, 3), seed=11)


@pytest.fixture(scope="module")
def sources(artifact):
    return emit.network_sources(artifact)


def hex_literals(text: str) -> list[float]:
    return [float.fromhex(m) for m in re.findall(r"-?0x[0-9a-f.]+p[+-]\d+(?=f)", text)]


def test_regeneration_is_byte_identical(artifact, tmp_path):
    reloaded = art.load(artifact.save(tmp_path / "a.json"))
    first = emit.emit(artifact, tmp_path / "one")
    second = emit.emit(reloaded, tmp_path / "two")
    assert [p.name for p in first] == ["network.c", "network.h", "sg_math.c", "sg_math.h"]
    for a, b in zip(first, second):
        assert a.read_bytes() == b.read_bytes(), a.name
    other = emit.network_sources(art.random_artifact((12, 40, 3), seed=12))
    assert other["network.c"] != emit.network_sources(artifact)["network.c"]


def test_header_carries_sha256_version_units_and_api(artifact, sources):
    h = sources["network.h"]
    assert artifact.sha256 in h and f'NETWORK_GENERATOR_VERSION "{GENERATOR_VERSION}"' in h
    for line in ("#define NETWORK_N_IN 12", "#define NETWORK_N_HIDDEN 40", "#define NETWORK_N_OUT 3"):
        assert line in h
    for stage in STAGES:
        assert re.search(rf"^void network_{stage}\(const float \w+\[NETWORK_N_\w+\], float \w+\[NETWORK_N_\w+\]\);",
                         h, re.M)
    assert "x[4] omega_dot_d_y [deg/s^2]" in h and "y[2] M_cmd_z [N*m]" in h and "row-major W[out][in]" in h
    assert not re.search(r"\d{4}-\d\d-\d\d|\d\d:\d\d:\d\d", h + sources["network.c"])  # no timestamps


def test_constants_are_exact_and_in_consumption_order(artifact, sources):
    c = sources["network.c"]
    table = c[c.index("network_neurons[NETWORK_N_HIDDEN]"):c.index("network_b2[NETWORK_N_OUT]")]
    got = np.array(hex_literals(table), dtype=np.float64)
    want = np.concatenate([np.concatenate([[artifact.b1[j]], artifact.W1[j], artifact.W2[:, j]])
                           for j in range(artifact.n_hidden)]).astype(np.float64)
    np.testing.assert_array_equal(got, want)
    gains = c[c.index("network_in_gain["):].split(";")[0]
    np.testing.assert_array_equal(np.array(hex_literals(gains)), artifact.input_map.gain.astype(np.float64))


def test_c_float_literals_round_trip():
    for v in (0.1, -1.2, 1e-45, -0.0, 3.4028234663852886e38, 2.0 ** -126):
        text = c_float(v)
        assert text.endswith("f")
        back = np.float32(float.fromhex(text[:-1]))
        assert back.view(np.uint32) == np.float32(v).view(np.uint32), text


def test_entry_name_is_checked_and_used(artifact):
    src = emit.network_sources(artifact, "nn_torque")
    assert "void nn_torque_eval(" in src["nn_torque.h"] and "#define NN_TORQUE_N_IN 12" in src["nn_torque.h"]
    for bad in ("Network", "sg_net", "9lives", "a-b"):
        with pytest.raises(CodegenError, match="--name"):
            emit.network_sources(artifact, bad)


def nm(obj) -> dict[str, str]:
    """{symbol: type letter} from nm."""
    out = subprocess.run(["nm", str(obj)], capture_output=True, text=True, check=True).stdout
    table = {}
    for line in out.splitlines():
        parts = line.split()
        table[parts[-1]] = parts[-2]
    return table


def test_x86_objects_reference_no_libm_no_malloc_no_mutable_globals(artifact):
    build = X86Runner(NetworkUnit(artifact)).build
    objects = {o.name: nm(o) for o in build.objects if o.name != LAYOUT_FILE.replace(".c", ".o")}
    assert set(objects) == {"network.o", "sg_math.o"}
    undefined = {s for table in objects.values() for s, t in table.items() if t == "U"}
    # the only external references, resolved by sg_math.o: the out-of-range tanh call and the table
    # that sg_inline_tanhf reads (-fPIC reaches it through the linker's GOT)
    assert undefined <= {"sg_tanhf", "sg_tanh_tab", "sg_crc32", "_GLOBAL_OFFSET_TABLE_"}, undefined
    assert not undefined & (LIBM | ALLOC)
    net = objects["network.o"]
    assert all(net[f"network_{s}"] == "T" for s in STAGES)  # real, global functions
    mutable = {s for table in objects.values() for s, t in table.items() if t in "DdBbCG"}
    assert not mutable, mutable


def arm_compile(src_dir, out, *extra):
    cmd = [flags.ARM_CC, *flags.COMMON, *flags.ARM_CPU, "-I", str(src_dir), *extra, str(src_dir / "network.c"),
           "-o", str(out)]
    res = subprocess.run(cmd, capture_output=True, text=True)
    assert res.returncode == 0, res.stderr
    return out


def test_arm_build_is_clean_and_the_mlp_loop_does_not_spill(artifact, tmp_path):
    """Cortex-M4: inputs and accumulators stay in registers (no spill), one vldr+vmul+vadd per MAC,
    tanh inlined (its only call is the out-of-range one), a neuron's weights loaded back to back."""
    assert shutil.which(flags.ARM_CC), f"{flags.ARM_CC} missing: run tools/setup.sh"
    write_sources(emit.network_sources(artifact), tmp_path)
    asm = arm_compile(tmp_path, tmp_path / "network.s", "-S").read_text()
    body = asm[asm.index("network_mlp:"):asm.index(".size\tnetwork_mlp")]
    assert "[sp" not in body  # no spills (the prologue uses push/vpush, not sp-relative access)
    unroll = emit.hidden_unroll(artifact.n_hidden)
    n_in, n_out = artifact.n_in, artifact.n_out
    counts = {op: len(re.findall(rf"^\s+{op}\b", body, re.M))
              for op in ("vmul.f32", "vadd.f32", "vldr.32", "bl", "vabs.f32")}
    # per neuron of the unrolled body: n_in + n_out MACs and tanh's 4 multiply-adds; loads: the
    # bias and the weights, tanh's 6 coefficients; before the loop: the inputs and b2.
    assert counts == {"vmul.f32": unroll * (n_in + n_out + 4), "vadd.f32": unroll * (n_in + n_out + 4),
                      "vldr.32": n_in + n_out + unroll * (1 + n_in + n_out + 6),
                      "bl": unroll, "vabs.f32": unroll}, counts
    assert set(re.findall(r"^\s+bl\s+(\w+)", body, re.M)) == {"sg_tanhf"}
    runs = [len(m.group(0).splitlines()) for m in re.finditer(r"(?:^\s+vldr\.32\b.*\n)+", body, re.M)]
    assert max(runs) >= n_in + 1, runs  # SG_LOADS_DONE: the bias and weights of a neuron in one run
    obj = arm_compile(tmp_path, tmp_path / "network.o", "-c")
    symbols = nm(obj)
    assert {s for s, t in symbols.items() if t == "U"} == {"sg_tanhf", "sg_tanh_tab", "sg_crc32"}


# The first (lenient) table's budget, kept as a regression guard: SPEC section 8 now states
# <= 3,000 cycles under the strict table and the static bound, which this path does not meet yet
# (issue 16: 3,857 sampled, static bound 4,603; the rework of the path is the open item).
LENIENT_BUDGET_CYCLES = 3500


def test_network_path_worst_case_cycles_within_budget():
    """Cycle model, ideal mode: the 50 vectors of each input class (inside, edges, outside,
    special values: saturated and non-finite rows take sg_tanhf's out-of-line path)."""
    a = art.random_artifact((12, 40, 3), seed=1)
    unit = NetworkUnit(a)
    classes = unit.cycle_classes(50, 0)
    records = {c: pack(unit, b).view(np.uint8).reshape(b.input.shape[0], -1) for c, b in classes.items()}
    prof = profile_entry(arm_build(unit).elf, "network_eval", records, ("ideal",))
    assert prof.cycles_lenient["ideal"]["max"] <= LENIENT_BUDGET_CYCLES, prof.cycles_lenient
    assert prof.cycles["ideal"]["max"] > prof.cycles_lenient["ideal"]["max"]  # the strict stalls are there
    # the special class reached sg_tanhf once per hidden neuron (the out-of-line path is measured)
    assert prof.functions["sg_tanhf"]["calls"]["max"] == a.n_hidden


def test_cli_codegen_writes_the_four_files(monkeypatch, capsys, tmp_path, artifact):
    monkeypatch.setattr(cli, "COMMANDS", ["host.cli.codegen"])
    path = artifact.save(tmp_path / "a.json")
    assert cli.main(["codegen", "--artifact", str(path), "--out", str(tmp_path / "gen")]) == 0
    assert sorted(p.name for p in (tmp_path / "gen").iterdir()) == ["network.c", "network.h", "sg_math.c", "sg_math.h"]
    assert cli.main(["codegen", "--artifact", str(path), "--out", str(tmp_path / "g2"), "--name", "Bad"]) == 2
    err = capsys.readouterr().err
    assert len(err.strip().splitlines()) == 1 and "--name" in err


def test_x86_build_refuses_flight_code_that_calls_libm(tmp_path):
    """Inside the Python process a tanhf call would silently bind to the host libm: refused."""
    src = tmp_path / "src"
    src.mkdir()
    (src / "bad.c").write_text("float tanhf(float);\nfloat f(float x);\nfloat f(float x) { return tanhf(x); }\n")
    with pytest.raises(FirmwareError, match="tanhf"):
        x86.compile_objects(src, tmp_path / "obj")
