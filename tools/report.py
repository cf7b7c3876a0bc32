"""Cycle, memory and stack report of any unit's step on the emulated Cortex-M4, written once.

The unit's ELF (records adapter: the state travels in each record) runs the unit's cycle
classes under the cycle model in the requested memory modes; the report gives, for the step
function and every function it calls, min / median / max cycles per class and mode, µs at
168 MHz, the share of the paper's 3.3 ms, flash and RAM of the unit's objects (map file), the
worst-case stack (static call graph + -fstack-usage, cross-checked by stack painting) and the
verdict against the unit's budgets.
"""
from __future__ import annotations

import numpy as np

from codegen.unit import Batch, Unit
from tools import size, stack
from tools.cycles import CLOCK_HZ, PAPER_BUDGET_CYCLES, profile_entry
from tools.errors import ToolError
from tools.m4.elf import Image
from tools.m4.memory import WAIT_STATES
from tools.m4.wcet import Analysis
from tools.runners import arm_build, pack


def cycle_report(unit: Unit, modes, per_class: int, seed: int, extra: dict[str, Batch] | None = None) -> dict:
    """JSON-ready report of the unit's step; `extra` adds classes of the caller's (e.g. a reference step)."""
    build = arm_build(unit, "records")
    image = Image(build.elf)
    classes = {**unit.cycle_classes(per_class, seed), **(extra or {})}
    records = {c: pack(unit, b).view(np.uint8).reshape(b.input.shape[0], -1) for c, b in classes.items()}
    prof = profile_entry(image, unit.step_symbol, records, modes, unit.max_instructions)
    sz = size.sizes(build.elf, build.map)
    objs = sz.of_objects(unit.objects)
    bound = stack.worst_case(image, build.su_files, unit.step_symbol)
    stack.check_against_paint(bound, prof.stack_painted)
    static = static_bounds(image, build.elf.parent / "src", unit.step_symbol, prof)
    rep = {
        "unit": unit.kind, "identity": unit.identity(), "entry_fn": unit.step_symbol, "elf": str(build.elf),
        "table": "strict", "cycles": prof.cycles, "cycles_lenient": prof.cycles_lenient, **static, "by_class": prof.by_class, "functions": prof.functions,
        "counts": {c: int(r.shape[0]) for c, r in records.items()}, "per_class": per_class,
        "flash_bytes": objs["flash"], "ram_bytes": objs["ram"],
        "state_bytes": unit.state_dtype.itemsize if unit.stateful else 0,
        "stack_bytes": bound.bytes, "stack_painted": prof.stack_painted, "stack_path": bound.path,
        "stack_problems": bound.problems, "newlib": build.newlib, "objects": list(unit.objects),
        "image_flash": sz.flash, "image_ram": sz.ram,
        "reserved": sz.reserved + image.symbol("_estack") - image.symbol("_sstack"),
        "budgets": {"cycles": unit.budgets.cycles, "cycles_art": unit.budgets.cycles_art,
                    "flash": unit.budgets.flash, "ram": unit.budgets.ram, "stack": unit.budgets.stack},
    }
    rep.update(unit.extra_cycle_facts(prof.functions, prof.by_class))
    return rep


def static_bounds(image: Image, sources, entry: str, prof) -> dict:
    """The static worst-case bound of the step (tools/m4/wcet.py) per table and memory mode, and a
    consistency check: no sampled count may exceed it."""
    an = Analysis(image, sources)
    fb = an.bound(entry)
    out = {"bound": {t: {m: fb.cycles[(t, m)] for m in ("ideal", "art")} for t in ("strict", "lenient")},
           "bound_loops": [{"function": f.name, "header": f"0x{h:08x}", "source": w, "header_runs_per_entry": k}
                           for f in an.analysed() for h, w, k in f.loops],
           "bound_art_parts": fb.art_parts}
    for table, sampled in (("strict", prof.cycles), ("lenient", prof.cycles_lenient)):
        for mode, b in out["bound"][table].items():
            if mode in sampled and sampled[mode]["max"] > b:
                raise ToolError(f"{entry}: sampled {sampled[mode]['max']} cycles ({table}, {mode}) exceed the "
                                f"static bound {b}: the bound or the profiler is wrong")
    return out


def worst_case(rep: dict, mode: str) -> int | None:
    """SPEC 8: the larger of the static bound and the sampled maximum, strict table."""
    if mode not in rep["cycles"]:
        return rep["bound"]["strict"].get(mode)
    return max(rep["bound"]["strict"][mode], rep["cycles"][mode]["max"])


def verdict(value, budget, unit: str) -> str:
    if budget is None:
        return "no budget stated"
    if value is None:
        return "unknown"
    if value <= budget:
        return f"within budget ({value} <= {budget} {unit})"
    share = f" ({100.0 * (value - budget) / budget:.0f} %)" if budget > 0 else ""
    return f"OVER budget by {value - budget} {unit}{share}"


def art_verdict(worst_art, worst_ideal, budget) -> str:
    """The art verdict; without an art budget (SPEC 8: a step that runs its code once per call, whose
    art figure its footprint sets) the figure and the flash-line misses it pays, 5 cycles each."""
    if budget is not None or worst_art is None or worst_ideal is None:
        return verdict(worst_art, budget, "cycles")
    misses = (worst_art - worst_ideal) // WAIT_STATES
    return (f"{worst_art} cycles, no budget (SPEC 8: set by the code it runs once per call); "
            f"{misses} flash-line misses over ideal (cold ART: about the distinct flash lines it touches)")


def cycle_text(rep: dict) -> list[str]:
    """The report as Markdown lines."""
    modes = list(rep["cycles"])
    lines = [f"unit {rep['identity']}, ELF {rep['elf']}",
             "vectors: " + ", ".join(f"{c} {n}" for c, n in rep["counts"].items()), "",
             "Timing table strict (every TRM stall rule, conservative reading; docs/cycle-model.md); "
             "lenient (the first table) beside it. The truth on the chip lies between them.", "",
             "Static bound: longest path of the ELF's control-flow graph with the loop bounds of the C "
             "(the worst case no input can exceed); sampled: the vectors below.", "",
             "| mode | sampled min | median | max | static bound | lenient max | lenient bound | worst µs @168 MHz "
             "| worst share of 3.3 ms |",
             "|---|---:|---:|---:|---:|---:|---:|---:|---:|"]
    for m in modes:
        s, bd = rep["cycles"][m], rep["bound"]["strict"].get(m)
        worst = max(s["max"], bd or 0)
        lines.append(f"| {m} | {s['min']} | {s['median']} | {s['max']} | {bd if bd is not None else '-'} | "
                     f"{rep['cycles_lenient'][m]['max']} | {rep['bound']['lenient'].get(m, '-')} | "
                     f"{worst / CLOCK_HZ * 1e6:.2f} | {100.0 * worst / PAPER_BUDGET_CYCLES:.2f} % |")
    for m in ("ideal", "art"):
        if m not in modes:
            lines.append(f"| {m} | - | - | - | {rep['bound']['strict'][m]} | - | {rep['bound']['lenient'][m]} | "
                         f"{rep['bound']['strict'][m] / CLOCK_HZ * 1e6:.2f} | "
                         f"{100.0 * rep['bound']['strict'][m] / PAPER_BUDGET_CYCLES:.2f} % |")
    loops = ", ".join(f"{lp['source']} x{lp['header_runs_per_entry']}" for lp in rep["bound_loops"]) or "none"
    parts = ", ".join(f"{k} {v}" for k, v in rep["bound_art_parts"].items())
    lines += ["", f"static bound: loops (source line x header runs per entry) {loops}; "
              f"art flash stalls bounded by source: {parts}"]
    lines += ["", "| class | " + " | ".join(f"{m} min / median / max" for m in modes) + " |",
              "|---|" + "---:|" * len(modes)]
    for c, row in rep["by_class"].items():
        lines.append(f"| {c} | " + " | ".join(f"{row[m]['min']} / {row[m]['median']} / {row[m]['max']}"
                                            for m in modes) + " |")
    lines += ["", "Per function, cycles per step (summed over its calls), min / median / max:", "",
              "| function | calls | mode | inclusive | exclusive |", "|---|---:|---|---:|---:|"]
    for fn, row in rep["functions"].items():
        for m in modes:
            inc, exc = row["inclusive"][m], row["exclusive"][m]
            lines.append(f"| {fn} | {row['calls']['max']} | {m} | {inc['min']} / {inc['median']} / {inc['max']}"
                         f" | {exc['min']} / {exc['median']} / {exc['max']} |")
    stack_txt = (f"{rep['stack_bytes']} B static worst case" if rep["stack_bytes"] is not None
                 else "unbounded: " + "; ".join(rep["stack_problems"]))
    b = rep["budgets"]
    worst, worst_art = worst_case(rep, "ideal"), worst_case(rep, "art")
    lines += ["",
              f"flash: {' + '.join(rep['objects'])} {rep['flash_bytes']} B (whole image {rep['image_flash']} B); "
              f"RAM: {rep['ram_bytes']} B static + {rep['state_bytes']} B caller-owned state (image {rep['image_ram']} B "
              f"+ harness arena and stack {rep['reserved']} B reserved); newlib linked: {'yes' if rep['newlib'] else 'no'}",
              f"stack: {stack_txt} via {' -> '.join(rep['stack_path'])}; painted in the emulator {rep['stack_painted']} B"]
    if rep.get("ours_nn_path_ideal_max") is not None:
        net = rep["network_inclusive"]["ideal"]["max"]
        lines.append(f"network inside the step: {net} cycles (ideal max); the step without it (NN path, ideal max): "
                     f"{rep['ours_nn_path_ideal_max']} cycles (information, not a SPEC budget)")
    lines += ["",
              "budget (SPEC 8, strict table, the larger of the static bound and the sampled max), step worst case "
              f"ideal: {verdict(worst, b['cycles'], 'cycles')}",
              f"budget, step worst case art: {art_verdict(worst_art, worst, b['cycles_art'])}",
              f"budget, flash: {verdict(rep['flash_bytes'], b['flash'], 'B')}",
              f"budget, RAM: {verdict(rep['ram_bytes'] + rep['state_bytes'], b['ram'], 'B')}",
              f"budget, stack: {verdict(rep['stack_bytes'], b['stack'], 'B')}"]
    return lines
