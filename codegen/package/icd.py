"""The flight package's interface control document (ICD.md), rendered from the bound units, the
configuration's values and the evidence measured at generation. Deterministic: no date, no
path. Every text that came from a file (configuration strings, artifact names) is escaped for
Markdown table cells."""
from __future__ import annotations

from pathlib import Path

import numpy as np

from codegen import GENERATOR_VERSION
from codegen.cgen import environment
from codegen.unit import Unit

TEMPLATES = Path(__file__).with_name("templates")
C_TYPES = {np.dtype("<f4"): "float", np.dtype("<u4"): "uint32_t", np.dtype("<i4"): "int32_t"}
ROLES = ("input", "output", "state")


def cell(text) -> str:
    """One Markdown table cell: no pipe, newline or backtick breaks out of it."""
    s = str(text).replace("\\", "\\\\").replace("|", "\\|").replace("`", "'")
    return " ".join(s.split())


def c_type(dtype: np.dtype, name: str) -> str:
    sub = dtype.fields[name][0]
    base = C_TYPES[sub.base]
    return f"{base}[{sub.shape[0]}]" if sub.shape else base


def field_rows(unit: Unit) -> dict[str, dict]:
    """role -> {"ctype": C type name, "rows": [(field, C type, unit, frame, range, meaning)], "documented": bool}."""
    docs = unit.field_docs()
    out = {}
    for role in ROLES:
        dtype = getattr(unit, f"{role}_dtype")
        if dtype is None:
            continue
        by_name = {d.name: d for d in docs.get(role, [])}
        rows = []
        for name in dtype.names:
            d = by_name.get(name)
            info = (d.unit, d.frame, d.range, d.meaning) if d else ("?", "?", "?", "not documented by the unit")
            rows.append(tuple(cell(x) for x in (name, c_type(dtype, name), *info)))
        out[role] = {"ctype": unit.c_types[role], "rows": rows, "documented": bool(by_name)}
    return out


def _cycles(ev: dict, clock_hz: int, budget: int) -> list[tuple]:
    rows = []
    for mode, s in ev["cycles"]["step"].items():
        rows.append((mode, s["min"], s["median"], s["max"], f"{s['max'] / clock_hz * 1e6:.2f}",
                     f"{100.0 * s['max'] / budget:.2f} %"))
    return rows


def _functions(ev: dict, limit: int = 8) -> list[tuple]:
    fns = ev["cycles"].get("functions", {})
    ranked = sorted(fns.items(), key=lambda kv: (-kv[1]["ideal"]["max"], kv[0]))[:limit]
    return [(cell(fn), *(row[m]["max"] for m in ("ideal", "art", "pessimistic") if m in row)) for fn, row in ranked]


def _config_rows(config: dict) -> list[tuple[str, str]]:
    rows = []
    for table in ("package", "pid", "limits", "timing", "earth"):
        for key, value in config.get(table, {}).items():
            rows.append((cell(f"{table}.{key}"), cell(value)))
    return rows


def render_icd(name: str, units: dict[str, Unit], config: dict, evidence: dict, flags: dict) -> str:
    clock, budget = evidence.get("clock_hz", 168_000_000), evidence.get("paper_budget_cycles", 554_400)
    unit_ctx = []
    for kind, unit in units.items():
        ev = evidence["units"][kind]
        unit_ctx.append({
            "kind": kind, "entry": unit.entry, "P": unit.entry.upper(), "identity": cell(unit.identity()),
            "stateful": unit.stateful, "fields": field_rows(unit),
            "status": [(cell(b.name), f"0x{b.mask:08x}", cell(b.meaning)) for b in unit.status_bits()],
            "cycles": _cycles(ev, clock, budget), "functions": _functions(ev),
            "reference": ev["cycles"].get("reference", {}), "memory": ev["memory"], "gate": ev["gate"],
            "selftest": ev["selftest_vectors"],
            "envelope": _envelope(unit),
        })
    ctx = {"name": name, "P": name.upper(), "generator_version": GENERATOR_VERSION, "units": unit_ctx,
           "period": config.get("timing", {}).get("control_period"), "config": _config_rows(config),
           "inputs": {k: {kk: cell(vv) for kk, vv in v.items()} for k, v in config.get("inputs", {}).items()},
           "flags": " ".join(flags.get("common", [])), "arm_cpu": " ".join(flags.get("arm_cpu", [])),
           "compiler": cell(flags.get("compiler", "")), "clock_mhz": clock / 1e6, "budget": budget,
           "package_build": evidence.get("package_build", {})}
    return environment(TEMPLATES).get_template("ICD.md.j2").render(ctx)


def _envelope(unit: Unit) -> list[tuple]:
    """The network envelope inside the controller (where the network flies), if the unit has one."""
    artifact = getattr(unit, "artifact", None)
    if unit.kind != "controller" or artifact is None:
        return []
    env = artifact.envelope
    return [(i, cell(n), cell(u), f"{float(lo):.9g}", f"{float(hi):.9g}")
            for i, (n, u, lo, hi) in enumerate(zip(env.names, env.units, env.min, env.max))]
