"""The ICD: every field of every unit documented exactly once with configuration-derived ranges,
status masks equal to the specs' constants (and to the emitted C macros), the timing figures
derived from the evidence, configuration and artifact text escaped, deterministic output."""
from __future__ import annotations

import copy
import dataclasses
import re
import subprocess

import numpy as np
import pytest

from codegen import units
from codegen.artifact import random_artifact
from codegen.errors import CodegenError
from codegen.package.icd import cell, render_icd
from codegen.unit import FieldDoc
from codegen.units.controller import spec as cs
from codegen.units.tanh import golden as tanh_golden
from codegen.units.tanh.params import example_params
from firmware.flags import ARM_CPU, COMMON
from host.sim.scenarios import configure_unit
from tests.codegen.units.unit_checks import example_unit

ROLES = ("input", "output", "state")
CLOCK, BUDGET = 168_000_000, 554_400
KP = [17.5, 54.25, 18.125]                       # not the default gains: they must come from the mapping
BASE = {"ctrl": 16_801, "tanh": 123_457}         # step maxima the evidence reports (ideal; art +1000, pess. +2000)


# ----------------------------------------------------------------------------- helpers (independent of icd.py)

def expected_c_type(dtype: np.dtype, name: str) -> str:
    sub = dtype.fields[name][0]
    base = {"f": "float", "u": "uint32_t", "i": "int32_t"}[sub.base.kind]
    assert sub.base.itemsize == 4
    return f"{base}[{sub.shape[0]}]" if sub.shape else base


def split_row(line: str) -> list[str]:
    """A Markdown table row split at its unescaped pipes (a backslash escapes the next character)."""
    cells, cur, i = [], "", 0
    while i < len(line):
        ch = line[i]
        if ch == "\\" and i + 1 < len(line):
            cur += line[i:i + 2]
            i += 2
            continue
        if ch == "|":
            cells.append(cur)
            cur = ""
        else:
            cur += ch
        i += 1
    cells.append(cur)
    assert cells[0].strip() == "" and cells[-1].strip() == "", line
    return [c.strip() for c in cells[1:-1]]


def section(text: str, heading: str) -> str:
    """The text from `heading` to the next heading of the same or a higher level."""
    level = len(heading) - len(heading.lstrip("#"))
    start = text.index(heading + "\n")
    rest = text[start + len(heading) + 1:]
    m = re.search(rf"^#{{1,{level}}} ", rest, flags=re.M)
    return rest[:m.start()] if m else rest


def unit_section(text: str, kind: str) -> str:
    m = re.search(rf"^## Unit `{kind}`: .*$", text, flags=re.M)
    assert m, kind
    return section(text, m.group(0))


def stats(mx: int) -> dict:
    return {"min": mx // 3, "median": mx // 2, "max": mx}


def unit_evidence(entry: str, base: int) -> dict:
    """The evidence in the shape the brief gives (selftest_vectors a count, golden mismatches)."""
    step = {"ideal": stats(base), "art": stats(base + 1000), "pessimistic": stats(base + 2000)}
    return {"entry": entry,
            "gate": {"vectors": 20000, "sequences": 4, "steps": 200, "pass": True,
                     "targets": {"golden": {"mismatches": 0}, "x86": {"mismatches": 0}, "arm": {"mismatches": 0}}},
            "selftest_vectors": 256,
            "cycles": {"step": step, "reference": {"ideal": 5000, "art": 7000, "pessimistic": 9000},
                       # the static bound: above the sampled max in ideal, below it in art (the
                       # worst case is the larger of the two in either case)
                       "bound": {"strict": {"ideal": base + 50, "art": base + 900}},
                       "step_lenient": {m: stats(v["max"] - 30) for m, v in step.items()},
                       "functions": {f"{entry}_step": step, f"{entry}_helper": {m: stats(7) for m in step}}},
            "memory": {"flash_bytes": 13000, "ram_bytes": 0, "state_bytes": 20, "stack_bytes": 360}}


def make_config(units_=("controller", "tanh"), **package) -> dict:
    return {"format": "staregen.controller-config", "version": 1,
            "package": {"name": "stare", "units": list(units_), **package},
            "pid": {"kp": list(KP), "ki": [0.0, 0.0, 0.0], "kd": [46.0, 77.0, 50.0], "integral_limit": 100.0},
            "limits": {"torque_limit": 1.0}, "timing": {"control_period": 0.1, "dwell_steps": 10},
            "earth": {"a": 6378137.0, "e2": 0.0066943799901413165, "rate": 7.29211585e-05, "mu": 3.986004418e14},
            "inputs": {"network": {"file": "network.json", "sha256": "ab" * 32},
                       "tanh": {"file": "tanh.toml", "sha256": "cd" * 32}}}


FLAGS = {"common": list(COMMON), "arm_cpu": list(ARM_CPU), "compiler": "arm-none-eabi-gcc (test) 13.2.1"}


def bound_units(artifact=None, config=None, with_tanh=True) -> dict:
    out = {"controller": configure_unit("controller", artifact=artifact or random_artifact((12, 40, 3), seed=1),
                                        config=config, name="stare")}
    if with_tanh:
        out["tanh"] = configure_unit("tanh", params=example_params(), name="stare_tanh")
    return out


def evidence_for(pkg: dict) -> dict:
    ev = {"units": {"controller": unit_evidence("stare", BASE["ctrl"])}, "clock_hz": CLOCK,
          "paper_budget_cycles": BUDGET}
    if "tanh" in pkg:
        ev["units"]["tanh"] = unit_evidence("stare_tanh", BASE["tanh"])
    return ev


def render(config=None, pkg=None, evidence=None) -> str:
    pkg = pkg or bound_units()
    return render_icd("stare", pkg, config or make_config(tuple(pkg)), evidence or evidence_for(pkg), FLAGS)


# ----------------------------------------------------------------------------- the units' docs

@pytest.mark.parametrize("kind", sorted(units.kinds()))
def test_field_docs_cover_exactly_the_dtype_fields(kind):
    unit = example_unit(units.get(kind))
    docs = unit.field_docs()
    assert set(docs) <= set(ROLES)
    for role in ROLES:
        dtype = getattr(unit, f"{role}_dtype")
        if dtype is None:
            assert not docs.get(role), (kind, role)
            continue
        names = [d.name for d in docs.get(role, [])]
        assert sorted(names) == sorted(dtype.names) and len(set(names)) == len(names), (kind, role, names)
        for d in docs[role]:
            assert isinstance(d, FieldDoc)
            assert all(isinstance(x, str) and x.strip() for x in (d.unit, d.frame, d.range, d.meaning)), d


@pytest.mark.parametrize("kind", sorted(units.kinds()))
def test_status_masks_are_distinct_single_purpose_and_in_the_emitted_header(kind):
    unit = example_unit(units.get(kind))
    bits = unit.status_bits()
    masks = [b.mask for b in bits]
    assert len({b.name for b in bits}) == len(bits)
    assert all(m > 0 for m in masks) and len(set(masks)) == len(masks)
    assert all(a & b == 0 for i, a in enumerate(masks) for b in masks[i + 1:])
    # the C header the unit emits defines each macro with the same value
    header = unit.sources()[unit.header]
    P = unit.entry.upper()
    for b in bits:
        m = re.search(rf"#define {P}_{b.name} \(?(\d+)u\)?\s", header)
        assert m, (kind, b.name)
        assert int(m.group(1)) == b.mask, (kind, b.name)


def test_status_masks_are_the_spec_constants():
    ctrl = {b.name: b.mask for b in example_unit(units.get("controller")).status_bits()}
    assert ctrl == {"STATUS_PID": cs.STATUS_PID, "STATUS_BOUNDS_MASK": cs.STATUS_BOUNDS_MASK,
                    "STATUS_INPUT_INVALID": cs.STATUS_INPUT_INVALID, "STATUS_SATURATED": cs.STATUS_SATURATED,
                    "STATUS_DWELL": cs.STATUS_DWELL, "STATUS_STATE_REPAIRED": cs.STATUS_STATE_REPAIRED,
                    "STATUS_INTEGRITY": cs.STATUS_INTEGRITY}
    assert ctrl["STATUS_BOUNDS_MASK"] == sum(1 << (cs.STATUS_BOUND_SHIFT + i) for i in range(cs.N_BOUNDS))
    tanh = {b.name: b.mask for b in example_unit(units.get("tanh")).status_bits()}
    assert tanh == {"STATUS_SINGULAR": tanh_golden.STATUS_SINGULAR,
                    "STATUS_INVALID_INPUT": tanh_golden.STATUS_INVALID_INPUT}
    assert example_unit(units.get("network")).status_bits() == []


def docs_by_name(unit) -> dict:
    return {(role, d.name): d for role, ds in unit.field_docs().items() for d in ds}


def test_ranges_follow_the_configuration_and_the_artifact():
    base = configure_unit("controller", artifact=random_artifact((12, 40, 3), seed=1)).config
    cfg = dataclasses.replace(base, torque_limit=0.375, dwell_steps=7, integral_limit=55.5)
    d = docs_by_name(configure_unit("controller", artifact=random_artifact((12, 40, 3), seed=1), config=cfg))
    assert "0.375" in d["output", "torque"].range and "1.0" not in d["output", "torque"].range
    assert "0..7" in d["state", "clean"].range
    assert "55.5" in d["state", "integral"].range
    assert str(cs.UTC_MS_MAX) in d["input", "utc_ms"].range and str(cs.LAT_BAM_MAX) in d["input", "lat"].range

    p = dataclasses.replace(example_params(), varpi_limit=1234.5)
    t = docs_by_name(configure_unit("tanh", params=p))
    assert f"{p.k1 + p.k2 + p.k3:.9g}" in t["output", "torque"].range
    assert "1234.5" in t["output", "varpi"].range and "1234.5" in t["state", "varpi"].range

    a = random_artifact((12, 40, 3), seed=1)
    env = dataclasses.replace(a.envelope, max=np.where(np.arange(12) == 4, np.float32(0.0625), a.envelope.max)
                              .astype(np.float32))
    n = docs_by_name(configure_unit("network", artifact=dataclasses.replace(a, envelope=env)))
    assert "x[4] [-0.015, 0.0625]" in n["input", "x"].range
    for i, (name, unit) in enumerate(zip(env.names, env.units)):
        assert f"x[{i}] {name}" in n["input", "x"].meaning and unit in n["input", "x"].unit


def test_network_output_bound_holds_for_wild_inputs():
    unit = configure_unit("network", artifact=random_artifact((12, 40, 3), seed=1))
    rng = np.random.default_rng(5)
    rec = np.zeros(20_000, dtype=unit.input_dtype)
    rec["x"] = rng.normal(0.0, 1e3, rec["x"].shape).astype(np.float32)
    y = unit.golden(None, rec)[0]["y"]
    text = unit.field_docs()["output"][0].range
    for k in range(y.shape[1]):
        lo, hi = map(float, re.search(rf"y\[{k}\] \[([-0-9.e+]+), ([-0-9.e+]+)\]", text).groups())
        assert lo * (1 + 1e-5) - 1e-6 <= y[:, k].min() and y[:, k].max() <= hi * (1 + 1e-5) + 1e-6


# ----------------------------------------------------------------------------- the rendered ICD

def test_icd_lists_every_field_of_every_unit_with_its_c_type():
    pkg = bound_units()
    text = render(pkg=pkg)
    for kind, unit in pkg.items():
        part = unit_section(text, kind)
        for role in ROLES:
            dtype = getattr(unit, f"{role}_dtype")
            table = section(part, f"### `{unit.entry}_{role}_t` ({role})")
            rows = [split_row(ln) for ln in table.splitlines() if ln.startswith("| `")]
            assert [r[0] for r in rows] == [f"`{n}`" for n in dtype.names], (kind, role)
            for r, name in zip(rows, dtype.names):
                assert r[1] == f"`{expected_c_type(dtype, name)}`" and len(r) == 6
                assert "not documented" not in r[5]


def test_timing_figures_are_derived_from_the_evidence():
    pkg = bound_units()
    ev = evidence_for(pkg)
    text = render(pkg=pkg, evidence=ev)
    for kind in pkg:
        timing = section(unit_section(text, kind), "### Timing on the STM32F417 (cycle model, 168 MHz)")
        rows = {r[0]: r for r in (split_row(ln) for ln in timing.splitlines()
                                  if ln.startswith("| ideal") or ln.startswith("| art") or ln.startswith("| pess"))}
        assert set(rows) == {"ideal", "art", "pessimistic"}
        cyc = ev["units"][kind]["cycles"]
        for mode, s in cyc["step"].items():
            bound = cyc["bound"]["strict"].get(mode)
            worst = max(s["max"], bound or 0)                # SPEC 8: the larger of bound and max
            us = worst / 168.0                               # 168 cycles per µs at 168 MHz
            share = 100.0 * worst / BUDGET
            assert rows[mode] == [mode, str(s["min"]), str(s["median"]), str(s["max"]),
                                  str(bound) if bound is not None else "-", str(cyc["step_lenient"][mode]["max"]),
                                  f"{us:.2f}", f"{share:.2f} %"]
        assert "ideal 5000, art 7000, pessimistic 9000 cycles" in timing
    # 16,851 cycles (the bound) are 100.30 µs: the figure is the worst case / 168, not a rounded constant
    assert f"| {BASE['ctrl'] + 50} | {BASE['ctrl'] - 30} | 100.30 |" in text


def test_configuration_flags_and_fp_environment_are_stated():
    text = render()
    conf = section(text, "## Configuration baked in")
    row = next(split_row(ln) for ln in conf.splitlines() if ln.startswith("| `pid.kp`"))
    assert row == ["`pid.kp`", "[17.5, 54.25, 18.125]"]
    build = section(text, "## Build requirements and floating-point environment")
    for flag in [*COMMON, *ARM_CPU]:
        assert flag in build, flag
    assert "-ffp-contract=off" in build and "SG_FP_CONTRACT_OFF" in build
    assert "round to nearest even" in build and "FZ = 0" in build and "DAZ = 0" in build and "MXCSR" in build
    assert "DN (default-NaN mode) may be 0 or 1" in " ".join(build.split())   # proven irrelevant (issue 25)
    for refused in ("-ffast-math", "-ffinite-math-only", "FLT_EVAL_METHOD", "-std=gnu"):
        assert refused in build
    assert "STARE_STATUS_SATURATED` | `0x%08x`" % cs.STATUS_SATURATED in text
    assert "add_subdirectory(path/to/stare stare_pkg)" in text
    assert "target_link_libraries(app PRIVATE stare stare_selftest)" in text
    example = text[text.index("```c"):]
    assert example.index("stare_init(") < example.index("stare_selftest()") < example.index("stare_step(")
    assert "every 0.1 s" in example


def test_text_from_files_cannot_break_a_table():
    cfg = make_config(name="a|b\n| injected | row |")
    cfg["inputs"]["network"]["file"] = "net|work\n.json"
    a = random_artifact((12, 40, 3), seed=1)
    env = dataclasses.replace(a.envelope, units=("deg|s`x",) + a.envelope.units[1:])
    text = render(cfg, pkg=bound_units(artifact=dataclasses.replace(a, envelope=env)))
    assert not any(ln.startswith("| injected") for ln in text.splitlines())
    for ln in text.splitlines():
        if ln.startswith("| `package.name`"):
            assert split_row(ln) == ["`package.name`", "a\\|b \\| injected \\| row \\|"]
        if ln.startswith("| network |"):
            assert split_row(ln)[1] == "net\\|work .json"
        if ln.startswith("| 0 | omega_d_x"):
            assert split_row(ln)[2] == "deg\\|s'x"
    # every table keeps its column count on every row
    for block in re.split(r"\n\s*\n", text):
        lines = [ln for ln in block.splitlines() if ln.startswith("|")]
        if lines:
            assert len({len(split_row(ln)) for ln in lines}) == 1, lines[0]
    assert cell("x`y|z\nw") == "x'y\\|z w" and cell("a\\|b") == "a\\\\\\|b"


def test_undocumented_unit_is_listed_and_said_so():
    pkg = bound_units(with_tanh=False)
    bare = copy.copy(pkg["controller"])
    bare.__class__ = type("Bare", (type(bare),), {"field_docs": lambda self: {}, "status_bits": lambda self: []})
    text = render(pkg={"controller": bare})
    table = section(unit_section(text, "controller"), "### `stare_state_t` (state)")
    assert "Not documented by the unit" in table
    rows = [split_row(ln) for ln in table.splitlines() if ln.startswith("| `")]
    assert [r[0] for r in rows] == ["`integral`", "`mode`", "`clean`", "`fault`"]
    assert all(r[5] == "not documented by the unit" for r in rows)


@pytest.mark.parametrize("names, problem", [(("no_such_field",), "no_such_field"), (("lat", "lat"), "twice")])
def test_docs_naming_a_missing_or_repeated_field_are_refused(names, problem):
    pkg = bound_units(with_tanh=False)
    odd = copy.copy(pkg["controller"])
    docs = [FieldDoc(n, "-", "-", "-", "-") for n in names]
    odd.__class__ = type("Odd", (type(odd),), {"field_docs": lambda self: {"input": docs}})
    with pytest.raises(CodegenError, match=problem):
        render(pkg={"controller": odd})


def test_deterministic_and_package_build_stated():
    first = render()
    assert first == render(pkg=bound_units())           # fresh units, same bytes
    pkg = bound_units()
    ev = {**evidence_for(pkg), "package_build": {"x86": {"selftest_mismatches": 0},
                                                 "arm": {"selftest_mismatches": 0, "reference_cycles": {}}}}
    text = render(pkg=pkg, evidence=ev)
    assert "returned 0 on x86, 0 on arm" in text
    # the manifest-shaped self-test evidence renders too
    ev["units"]["controller"]["selftest_vectors"] = {"n": 8, "classes": {"inside": 5, "edges": 3}, "targets": {}}
    assert "Self-test vectors: 8 (inside 5, edges 3)." in render(pkg=pkg, evidence=ev)


def test_input_file_names_are_escaped_for_markdown_and_html():
    """Issue 25 defect 15: a file name is any text but `/`; the inputs table shows it literally."""
    cfg = make_config()
    cfg["inputs"]["network"]["file"] = "<img src=x onerror=alert(1)>[a](javascript:x)_*.json"
    text = render(cfg)
    (row,) = [ln for ln in text.splitlines() if ln.startswith("| network |")]
    assert "<img" not in text and not re.search(r"(?<!\\)\]\(javascript:", text)   # no raw tag, no link
    assert split_row(row)[1] == "&lt;img src=x onerror=alert(1)&gt;\\[a\\](javascript:x)\\_\\*.json"
# ----------------------------------------------------------------------------- issue 25, defect 21

def evidence_with_runs(pkg: dict) -> dict:
    """evidence_for plus what tools/package.py measures since issue 25: the reference step's
    output words, the record sizes, the self-test's cycles and stack in the ARM image."""
    ev = evidence_for(pkg)
    for kind, unit in pkg.items():
        e = ev["units"][kind]
        e["selftest_vectors"] = {"n": 256, "classes": {}, "targets": {},
                                 "reference_output_words": [f"0x{0x3f800000 + 17 * i + len(kind):08x}"
                                                            for i in range(unit.output_dtype.itemsize // 4)]}
        e["memory"]["record_bytes"] = {r: getattr(unit, f"{r}_dtype").itemsize for r in ROLES
                                       if getattr(unit, f"{r}_dtype") is not None}
        e["memory"]["tables_in"] = unit.tables_in
    ev["package_build"] = {"x86": {"selftest_mismatches": 0},
                           "arm": {"selftest_mismatches": 0, "reference_cycles": {},
                                   "selftest_cycles": {"ideal": 912_345, "art": 1_391_234, "pessimistic": 2_015_678},
                                   "selftest_stack_bytes": 396}}
    return ev


def test_integrity_check_is_in_the_call_sequence_and_the_example():
    pkg = bound_units()
    header = pkg["controller"].sources()["stare.h"]
    m = re.search(r"uint32_t (\w+_integrity_check)\((\w+) \*state\);", header)   # what the C declares
    assert m and m.group(2) == "stare_state_t"
    text = render(pkg=pkg, evidence=evidence_with_runs(pkg))
    calls = section(text, "## Call sequence")
    assert f"`{m.group(1)}(&stare_state)`" in calls
    example = text[text.index("```c"):]
    assert example.index("stare_init(") < example.index(f"{m.group(1)}(&stare_state)")
    assert example.count(f"{m.group(1)}(&stare_state)") == 2          # at start-up and in a background tick
    ccm = section(unit_section(text, "controller"), "### Memory")
    assert f"`{m.group(1)}()`" in ccm and "tables_crc32()` against" not in ccm


def test_the_public_header_reaches_the_tables_crc(tmp_path):
    """stare.h, the header the firmware includes, declares (by including the network's header) the
    CRC function and value that stare_integrity_check compares."""
    for name, text in bound_units(with_tanh=False)["controller"].sources().items():
        (tmp_path / name).write_text(text)
    (tmp_path / "user.c").write_text('#include "stare.h"\n'
                                     "int tables_intact(void);\n"
                                     "int tables_intact(void) { return stare_nn_tables_crc32() == STARE_NN_TABLES_CRC32; }\n")
    res = subprocess.run(["gcc", *COMMON, "-I", str(tmp_path), "-c", str(tmp_path / "user.c"), "-o",
                          str(tmp_path / "user.o")], capture_output=True, text=True)
    assert res.returncode == 0, res.stderr


def test_reference_words_selftest_run_and_record_sizes_are_stated():
    pkg = bound_units()
    ev = evidence_with_runs(pkg)
    text = render(pkg=pkg, evidence=ev)
    for kind, unit in pkg.items():
        part = unit_section(text, kind)
        words = ev["units"][kind]["selftest_vectors"]["reference_output_words"]
        assert f"`{' '.join(words)}`" in section(part, "### Timing on the STM32F417 (cycle model, 168 MHz)")
        memory = section(part, "### Memory")
        for role, n in ev["units"][kind]["memory"]["record_bytes"].items():
            assert f"`sizeof({unit.entry}_{role}_t)` = {n} B" in memory, (kind, role)
    selftest = section(text, "## Self-test")
    arm = ev["package_build"]["arm"]
    for mode, cycles in arm["selftest_cycles"].items():
        assert f"{cycles} cycles {mode} ({cycles / CLOCK * 1e3:.2f} ms)" in selftest
    assert f"uses {arm['selftest_stack_bytes']} B of stack" in selftest


def test_ccm_rule_moves_the_package_tables_only():
    pkg = bound_units()
    text = render(pkg=pkg, evidence=evidence_with_runs(pkg))
    memory = section(unit_section(text, "controller"), "### Memory")
    assert "*(.sg_tables .sg_tables.*)" in memory and "> CCM AT > FLASH" in memory
    assert ".rodata" not in memory                       # not every read-only section of the firmware
    # the generated C puts its tables there (GCC / clang only)
    sources = bound_units(with_tanh=False)["controller"].sources()
    assert "#define SG_TABLE(section_name) __attribute__((section(section_name)))" in sources["sg_math.h"]
    assert re.search(r'static const float stare_nn_neurons\[.*\] SG_TABLE\("\.sg_tables\.stare_nn_neurons"\) =',
                     sources["stare_nn.c"])


def test_compilers_and_math_errno_are_stated():
    build = section(render(), "## Build requirements and floating-point environment")
    for needed in ("clang", "armclang", "IAR", "--target=thumbv7em-none-eabihf", "-fno-math-errno", "`ARMClang`"):
        assert needed in build, needed
