"""The flight package's interface control document (ICD.md), rendered from the bound units (their
records, field docs and status bits), the configuration's values and the evidence measured at
generation. Deterministic: no date, no path, no dict order other than the inputs'.

Every text that came from a file (configuration strings, artifact names and units, file names)
goes through `cell` before it reaches the Markdown: no `|`, newline or backtick can break out of
a table cell or a code span.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

from codegen import GENERATOR_VERSION
from codegen.cgen import check_name, environment
from codegen.errors import CodegenError
from codegen.markdown import escape as markdown_escape
from codegen.unit import Unit

TEMPLATES = Path(__file__).with_name("templates")
C_TYPES = {np.dtype("<f4"): "float", np.dtype("<u4"): "uint32_t", np.dtype("<i4"): "int32_t"}
ROLES = ("input", "output", "state")
MODES = ("ideal", "art", "pessimistic")
NOT_DOCUMENTED = "not documented by the unit"


def cell(text) -> str:
    """One Markdown table cell (or code span): no pipe, newline or backtick breaks out of it.
    Backslashes are doubled first so an escaped pipe cannot be un-escaped; every run of
    whitespace (newlines included) becomes one space."""
    s = str(text).replace("\\", "\\\\").replace("|", "\\|").replace("`", "'")
    return " ".join(s.split())


def c_type(dtype: np.dtype, name: str) -> str:
    """The C type of one record field: float / uint32_t / int32_t, with its array length."""
    sub = dtype.fields[name][0]
    base = C_TYPES[sub.base]
    return f"{base}[{sub.shape[0]}]" if sub.shape else base


def field_rows(unit: Unit) -> dict[str, dict]:
    """role -> {"ctype": the C type of the record, "rows": [(field, C type, unit, frame, range,
    meaning)] in dtype order, "documented": how many fields the unit documents}. A documented name
    that is not a field of the record, or a field documented twice, is refused."""
    docs = unit.field_docs()
    out = {}
    for role in ROLES:
        dtype = getattr(unit, f"{role}_dtype")
        given = list(docs.get(role, []))
        if dtype is None:
            if given:
                raise CodegenError(f"{unit.kind}: documents {role} fields but has no {role} record")
            continue
        by_name = {}
        for d in given:
            if d.name not in dtype.names:
                raise CodegenError(f"{unit.kind}: documents {role} field {d.name!r}, not in {dtype.names}")
            if d.name in by_name:
                raise CodegenError(f"{unit.kind}: documents {role} field {d.name!r} twice")
            by_name[d.name] = d
        rows = []
        for name in dtype.names:
            d = by_name.get(name)
            info = (d.unit, d.frame, d.range, d.meaning) if d else ("?", "?", "?", NOT_DOCUMENTED)
            rows.append(tuple(cell(x) for x in (name, c_type(dtype, name), *info)))
        out[role] = {"ctype": cell(unit.c_types[role]), "rows": rows, "documented": len(by_name)}
    return out


def micro_seconds(cycles: int, clock_hz: int) -> str:
    return f"{cycles / clock_hz * 1e6:.2f}"


def _modes(stats: dict) -> list[str]:
    return [m for m in MODES if m in stats] + [m for m in stats if m not in MODES]


def _cycles(ev: dict, clock_hz: int, budget: int) -> list[tuple]:
    """Per mode: sampled min / median / max, the static bound and the lenient max (or "-"), and
    the worst case (the larger of bound and max) in µs and as a share of the paper's budget."""
    step = ev["cycles"]["step"]
    bound = ev["cycles"].get("bound", {}).get("strict", {})
    lenient = ev["cycles"].get("step_lenient", {})
    rows = []
    for m in _modes(step):
        worst = max(step[m]["max"], int(bound.get(m, 0)))
        rows.append((cell(m), step[m]["min"], step[m]["median"], step[m]["max"], bound.get(m, "-"),
                     lenient.get(m, {}).get("max", "-"), micro_seconds(worst, clock_hz),
                     f"{100.0 * worst / budget:.2f} %"))
    return rows


def _functions(ev: dict, modes: list[str], limit: int = 8) -> list[tuple]:
    """The costliest functions (max cycles, inclusive), ranked by the first mode."""
    fns = ev["cycles"].get("functions", {})
    first = modes[0] if modes else None
    ranked = sorted(fns.items(), key=lambda kv: (-kv[1].get(first, {}).get("max", 0), kv[0]))[:limit]
    return [(cell(fn), *(str(row[m]["max"]) if m in row else "-" for m in modes)) for fn, row in ranked]


def _selftest(ev: dict) -> dict:
    """Self-test vectors as evidence gives them: a count, or {"n", "classes", "targets"}."""
    s = ev.get("selftest_vectors", 0)
    if isinstance(s, dict):
        return {"n": s.get("n", 0), "classes": [(cell(c), k) for c, k in s.get("classes", {}).items()]}
    return {"n": s, "classes": []}


def _gate(ev: dict) -> dict:
    g = ev.get("gate", {})
    targets = g.get("targets", {})
    words = [(cell(t), r["mismatches"]) for t, r in targets.items() if t != "golden" and "mismatches" in r]
    return {"vectors": g.get("vectors", 0), "sequences": g.get("sequences", 0), "steps": g.get("steps", 0),
            "targets": words, "pass": bool(g.get("pass", False))}


def _value(v) -> str:
    if isinstance(v, (list, tuple)):
        return "[" + ", ".join(_value(x) for x in v) + "]"
    return repr(v) if isinstance(v, float) else str(v)


def _config_rows(config: dict) -> list[tuple[str, str]]:
    rows = [(cell(k), cell(_value(config[k]))) for k in ("format", "version") if k in config]
    for table, values in config.items():
        if table in ("format", "version", "inputs") or not isinstance(values, dict):
            continue
        for key, value in values.items():
            rows.append((cell(f"{table}.{key}"), cell(_value(value))))
    return rows


def _inputs(config: dict) -> list[tuple[str, str, str]]:
    """(role, file name, sha256 prefix): a file may be named `<img src=x onerror=...>.json`, so its
    name is escaped for Markdown and the HTML a renderer passes through, not only kept in its cell."""
    return [(markdown_escape(k), markdown_escape(v.get("file", "")), cell(str(v.get("sha256", ""))[:16]))
            for k, v in config.get("inputs", {}).items() if isinstance(v, dict)]


def _period(unit: Unit):
    """The control period a unit bakes in (s), if it states one."""
    cfg = getattr(unit, "config", None)
    period = getattr(cfg, "control_period", None) if cfg is not None else getattr(unit, "period", None)
    return None if period is None else float(period)


def _envelope(unit: Unit) -> dict | None:
    """The network envelope inside the controller (where the network flies), as emitted."""
    artifact = getattr(unit, "artifact", None)
    if unit.kind != "controller" or artifact is None:
        return None
    if getattr(unit.config, "pid_only", False):
        return {"pid_only": True, "rows": []}
    env = artifact.envelope
    return {"pid_only": False,
            "rows": [(i, cell(n), cell(u), str(np.float32(lo)), str(np.float32(hi)))
                     for i, (n, u, lo, hi) in enumerate(zip(env.names, env.units, env.min, env.max))]}


def _code(words) -> str:
    """Flags for one code span."""
    return cell(" ".join(str(w) for w in words))


def _reference_words(ev: dict) -> list[str]:
    """The reference step's expected output words as the evidence records them (hex), if it does."""
    s = ev.get("selftest_vectors")
    return [cell(w) for w in s.get("reference_output_words", [])] if isinstance(s, dict) else []


def _records(unit: Unit, ev: dict) -> list[tuple[str, int]]:
    """(C type, sizeof) of each record the evidence measured, in input, output, state order."""
    sizes = ev.get("memory", {}).get("record_bytes", {})
    return [(cell(unit.c_types[r]), int(sizes[r])) for r in ROLES if r in sizes and r in unit.c_types]


def _selftest_run(evidence: dict, clock: int) -> dict | None:
    """The self-test's cycles per mode, time and stack in the STM32F417 image's emulator run."""
    arm = evidence.get("package_build", {}).get("arm", {})
    cycles = arm.get("selftest_cycles")
    if not cycles:
        return None
    return {"cycles": [(cell(m), c) for m, c in cycles.items()],
            "ms": {m: f"{c / clock * 1e3:.2f}" for m, c in cycles.items()},
            "stack": arm.get("selftest_stack_bytes")}


def unit_context(name: str, kind: str, unit: Unit, ev: dict, clock: int, budget: int) -> dict:
    modes = _modes(ev["cycles"]["step"])
    return {
        "kind": cell(kind), "entry": unit.entry, "P": unit.entry.upper(), "identity": cell(unit.identity()),
        "stateful": unit.stateful, "step": unit.step_symbol, "init": unit.init_symbol,
        "c_types": {r: cell(t) for r, t in unit.c_types.items()}, "period": _period(unit),
        "fields": field_rows(unit),
        "status": [(cell(b.name), f"0x{b.mask:08x}", cell(b.meaning)) for b in unit.status_bits()],
        "cycles": _cycles(ev, clock, budget), "modes": [cell(m) for m in modes],
        "functions": _functions(ev, modes),
        "reference": [(cell(m), c) for m, c in ev["cycles"].get("reference", {}).items()],
        "is_reference_unit": unit.entry == name, "memory": ev["memory"], "gate": _gate(ev),
        "selftest": _selftest(ev), "envelope": _envelope(unit), "integrity": unit.integrity_symbol,
        "reference_words": _reference_words(ev), "records": _records(unit, ev),
    }


def render_icd(name: str, units: dict[str, Unit], config: dict, evidence: dict, flags: dict) -> str:
    """ICD.md of the package `name`: units {"controller": ..., and any configured "tanh", "rbf", ...} bound to the
    configuration `config` (the configuration file's mapping, plus "inputs": {role: {"file",
    "sha256"}}), `evidence` as tools/package.py measures it ({"units": {kind: {...}}, "clock_hz",
    "paper_budget_cycles", optionally "package_build"}), `flags` {"common", "arm_cpu",
    "compiler", optionally "signed": whether the manifest is signed, "gcc_only"}. The same arguments give the same bytes."""
    check_name(name)
    clock = int(evidence.get("clock_hz", 168_000_000))
    budget = int(evidence.get("paper_budget_cycles", 554_400))
    missing = [k for k in units if k not in evidence.get("units", {})]
    if missing:
        raise CodegenError(f"ICD: no evidence for unit(s) {', '.join(missing)}")
    unit_ctx = [unit_context(name, kind, unit, evidence["units"][kind], clock, budget) for kind, unit in units.items()]
    main = next((u for u in unit_ctx if u["is_reference_unit"]), unit_ctx[0])
    ctx = {
        "name": name, "P": name.upper(), "generator_version": GENERATOR_VERSION, "units": unit_ctx, "main": main,
        "others": [u for u in unit_ctx if u is not main],
        "period": config.get("timing", {}).get("control_period"), "config": _config_rows(config),
        "inputs": _inputs(config), "flags": _code(flags.get("common", [])),
        "arm_cpu": _code(flags.get("arm_cpu", [])), "compiler": cell(flags.get("compiler", "")),
        "clock_mhz": f"{clock / 1e6:g}", "budget": budget, "budget_ms": f"{budget / clock * 1e3:g}",
        "package_build": [(cell(t), r.get("selftest_mismatches")) for t, r in evidence.get("package_build", {}).items()],
        "signed": bool(flags.get("signed", False)),
        "selftest_run": _selftest_run(evidence, clock), "gcc_only": _code(flags.get("gcc_only", [])),
    }
    return environment(TEMPLATES).get_template("ICD.md.j2").render(ctx)
