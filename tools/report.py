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
from tools.m4.elf import Image
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
    rep = {
        "unit": unit.kind, "identity": unit.identity(), "entry_fn": unit.step_symbol, "elf": str(build.elf),
        "cycles": prof.cycles, "by_class": prof.by_class, "functions": prof.functions,
        "counts": {c: int(r.shape[0]) for c, r in records.items()}, "per_class": per_class,
        "flash_bytes": objs["flash"], "ram_bytes": objs["ram"],
        "state_bytes": unit.state_dtype.itemsize if unit.stateful else 0,
        "stack_bytes": bound.bytes, "stack_painted": prof.stack_painted, "stack_path": bound.path,
        "stack_problems": bound.problems, "newlib": build.newlib, "objects": list(unit.objects),
        "image_flash": sz.flash, "image_ram": sz.ram,
        "reserved": sz.reserved + image.symbol("_estack") - image.symbol("_sstack"),
        "budgets": {"cycles": unit.budgets.cycles, "flash": unit.budgets.flash, "ram": unit.budgets.ram,
                    "stack": unit.budgets.stack},
    }
    rep.update(unit.extra_cycle_facts(prof.functions, prof.by_class))
    return rep


def verdict(value, budget, unit: str) -> str:
    if budget is None:
        return "no budget stated"
    if value is None:
        return "unknown"
    if value <= budget:
        return f"within budget ({value} <= {budget} {unit})"
    return f"OVER budget by {value - budget} {unit} ({100.0 * (value - budget) / budget:.0f} %)"


def cycle_text(rep: dict) -> list[str]:
    """The report as Markdown lines."""
    modes = list(rep["cycles"])
    lines = [f"unit {rep['identity']}, ELF {rep['elf']}",
             "vectors: " + ", ".join(f"{c} {n}" for c, n in rep["counts"].items()), "",
             "| mode | min | median | max | max µs @168 MHz | max share of 3.3 ms |", "|---|---:|---:|---:|---:|---:|"]
    for m in modes:
        s = rep["cycles"][m]
        lines.append(f"| {m} | {s['min']} | {s['median']} | {s['max']} | {s['max'] / CLOCK_HZ * 1e6:.2f} | "
                     f"{100.0 * s['max'] / PAPER_BUDGET_CYCLES:.2f} % |")
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
    worst = rep["cycles"]["ideal"]["max"] if "ideal" in rep["cycles"] else None
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
              f"budget (SPEC 8), step worst case ideal: {verdict(worst, b['cycles'], 'cycles')}",
              f"budget, flash: {verdict(rep['flash_bytes'], b['flash'], 'B')}",
              f"budget, RAM: {verdict(rep['ram_bytes'] + rep['state_bytes'], b['ram'], 'B')}",
              f"budget, stack: {verdict(rep['stack_bytes'], b['stack'], 'B')}"]
    return lines
