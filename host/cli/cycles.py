"""`staregen cycles [--entry network] --artifact FILE [--mode ideal|art|pessimistic|all] [--json FILE] [--md FILE]`,
`staregen cycles --entry tanh --params FILE [--period S] [--mode ...]` (paper 000's tanh law step),
`staregen cycles --entry controller [--artifact FILE] [--mode ...]` (the whole Fig. 2 step, NN and
PID paths reported apart; host/controller_cycles.py).

Generates the network path C from the artifact, builds the STM32F417 ELF, runs input classes
(inside the envelope, on its bounds, outside it, special values) through the harness in the
emulator under the Cortex-M4 cycle model, and reports per entry point and per function:
min / median / max cycles, µs at 168 MHz, share of the paper's 3.3 ms, flash, RAM and the
worst-case stack (static bound, cross-checked by stack painting). The network path is the
entry `network` (its C function `<name>_eval`).
"""
from __future__ import annotations

import argparse

import numpy as np

from host.errors import HostError
from codegen import atomic
from tools.cycles import CLOCK_HZ, PAPER_BUDGET_CYCLES, profile_entry
from tools.m4.profile import MODES

DEFAULT_PER_CLASS = 250
# SPEC section 8 budgets of the network path.
BUDGET_CYCLES = 3_500
BUDGET_FLASH = 16 * 1024
BUDGET_STACK = 512


def register(subparsers) -> None:
    parser = subparsers.add_parser("cycles", help="cycle, memory and stack report of the ARM build (emulated Cortex-M4)")
    parser.add_argument("--entry", default="network", choices=sorted(ENTRIES),
                        help="entry point: network (needs --artifact, default), controller (the whole Fig. 2 "
                             "step; --artifact, default the stand-in) or tanh (needs --params)")
    parser.add_argument("--artifact", metavar="FILE", help="model artifact (entry network)")
    parser.add_argument("--params", metavar="FILE", help="tanh-law parameter file, .toml/.json (entry tanh)")
    parser.add_argument("--period", type=float, default=0.1, metavar="S",
                        help="control period baked into the tanh step, s (entry tanh; default 0.1)")
    parser.add_argument("--mode", default="ideal", choices=[*MODES, "all"],
                        help="flash memory model (default ideal: 0 wait states); all = the three")
    parser.add_argument("--per-class", type=int, default=DEFAULT_PER_CLASS, metavar="N",
                        help=f"vectors per input class (default {DEFAULT_PER_CLASS})")
    parser.add_argument("--seed", type=int, default=0, help="vector seed (default 0)")
    parser.add_argument("--json", metavar="FILE", help="write the report as JSON")
    parser.add_argument("--md", metavar="FILE", help="write the report as Markdown")
    parser.set_defaults(func=run)


def class_vectors(envelope, per_class: int, seed: int) -> dict[str, np.ndarray]:
    """per_class rows of each gate class (codegen.units.network.vectors), as float32 (N, n_in)."""
    from codegen.units.network import vectors

    share = min(vectors.SHARE_BOUND, vectors.SHARE_OUTSIDE, vectors.SHARE_SPECIAL)
    vs = vectors.gate_vectors(envelope, int(np.ceil(per_class / share)) + 1, seed)
    out = {}
    for k, name in enumerate(vectors.KINDS):
        rows = vs.x[vs.kind == k][:per_class]
        if rows.shape[0] < per_class:
            raise HostError(f"cycles: only {rows.shape[0]} vectors of class {name}")
        out[name] = np.ascontiguousarray(rows)
    return out


def network_report(a, name: str, modes, per_class: int, seed: int) -> tuple[dict, dict]:
    """(JSON entry, extra facts for the text reports) of the network path."""
    from firmware import arm
    from tools import size, stack
    from tools.m4.elf import Image

    build = arm.network_build(a, name)
    image = Image(build.elf)
    entry_fn = f"{name}_eval"
    classes = class_vectors(a.envelope, per_class, seed)
    records = {c: x.view(np.uint8).reshape(x.shape[0], -1) for c, x in classes.items()}
    prof = profile_entry(image, entry_fn, records, modes)
    sz = size.sizes(build.elf, build.map)
    path = sz.of_objects([f"{name}.o", "sg_math.o"])
    bound = stack.worst_case(image, build.su_files, entry_fn)
    stack.check_against_paint(bound, prof.stack_painted)
    entry = {
        "cycles": prof.cycles,
        "flash_bytes": path["flash"],
        "ram_bytes": path["ram"],
        "stack_bytes": bound.bytes,
        "functions": prof.functions,
    }
    facts = {"entry_fn": entry_fn, "elf": str(build.elf), "by_class": prof.by_class,
             "counts": {c: int(x.shape[0]) for c, x in classes.items()},
             "image_flash": sz.flash, "image_ram": sz.ram,
             "reserved": sz.reserved + image.symbol("_estack") - image.symbol("_sstack"),
             "stack_painted": prof.stack_painted, "stack_path": bound.path,
             "stack_problems": bound.problems, "newlib": build.newlib}
    return entry, facts


def _us(cycles: int) -> float:
    return cycles / CLOCK_HZ * 1e6


def _share(cycles: int) -> str:
    return f"{100.0 * cycles / PAPER_BUDGET_CYCLES:.2f} %"


def _verdict(value, budget, unit) -> str:
    if value is None:
        return "unknown"
    if value <= budget:
        return f"within budget ({value} <= {budget} {unit})"
    return f"OVER budget by {value - budget} {unit} ({100.0 * (value - budget) / budget:.0f} %)"


def text_report(name: str, entry: dict, facts: dict, modes) -> list[str]:
    lines = [f"entry {name} ({facts['entry_fn']}), ELF {facts['elf']}",
             "vectors: " + ", ".join(f"{c} {n}" for c, n in facts["counts"].items()),
             "",
             "| mode | min | median | max | max µs @168 MHz | max share of 3.3 ms |",
             "|---|---:|---:|---:|---:|---:|"]
    for m in modes:
        s = entry["cycles"][m]
        lines.append(f"| {m} | {s['min']} | {s['median']} | {s['max']} | {_us(s['max']):.2f} | {_share(s['max'])} |")
    lines += ["", "Per input class (max cycles): " + "; ".join(
        f"{c}: " + ", ".join(f"{m} {facts['by_class'][c][m]['max']}" for m in modes) for c in facts["by_class"])]
    lines += ["", "Per function, cycles per evaluation (summed over its calls), min / median / max:", "",
              "| function | calls | mode | inclusive | exclusive |", "|---|---:|---|---:|---:|"]
    for fn, row in entry["functions"].items():
        for m in modes:
            inc, exc = row["inclusive"][m], row["exclusive"][m]
            lines.append(f"| {fn} | {row['calls']['max']} | {m} | {inc['min']} / {inc['median']} / {inc['max']}"
                         f" | {exc['min']} / {exc['median']} / {exc['max']} |")
    worst = entry["cycles"]["ideal"]["max"] if "ideal" in entry["cycles"] else None
    stack_txt = (f"{entry['stack_bytes']} B static worst case" if entry["stack_bytes"] is not None
                 else "unbounded: " + "; ".join(facts["stack_problems"]))
    lines += ["",
              f"flash: network path {entry['flash_bytes']} B (whole image {facts['image_flash']} B); "
              f"RAM: network path {entry['ram_bytes']} B (image {facts['image_ram']} B + harness arena and stack "
              f"{facts['reserved']} B reserved); newlib linked: {'yes' if facts['newlib'] else 'no'}",
              f"stack: {stack_txt} via {' -> '.join(facts['stack_path'])}; painted in the emulator "
              f"{facts['stack_painted']} B",
              "",
              f"budget (SPEC 8), network path worst case ideal: {_verdict(worst, BUDGET_CYCLES, 'cycles')}",
              f"budget, network path flash: {_verdict(entry['flash_bytes'], BUDGET_FLASH, 'B')}",
              f"budget, stack: {_verdict(entry['stack_bytes'], BUDGET_STACK, 'B')}"]
    return lines


def run_network(args: argparse.Namespace, modes) -> int:
    from codegen import artifact as art

    if not args.artifact:
        raise HostError("--entry network needs --artifact FILE")
    a = art.load(args.artifact)
    name = "network"
    entry, facts = network_report(a, name, modes, args.per_class, args.seed)
    lines = text_report(name, entry, facts, modes)
    return publish(args, name, entry, lines, f"{args.artifact} ({a.shape_text})")


def publish(args: argparse.Namespace, entry_name: str, entry: dict, lines: list[str], title: str) -> int:
    """Print the report; write it as JSON ({"entries": {name: entry}}) and Markdown when asked."""
    print("\n".join(lines))
    if args.json:
        atomic.write_json(args.json, {"entries": {entry_name: entry}})
        print(f"wrote {args.json}")
    if args.md:
        atomic.write_text(args.md, f"# Cycle report: {title}\n\n" + "\n".join(lines) + "\n")
        print(f"wrote {args.md}")
    return 0


def run_tanh(args: argparse.Namespace, modes) -> int:
    """tanh_step of paper 000's saturation law (host/tanh_sil.py builds, classes, report)."""
    from codegen.units.tanh.params import load_params
    from host import tanh_sil

    if not args.params:
        raise HostError("--entry tanh needs --params FILE (e.g. docs/tanh_paper000.toml)")
    if not (np.isfinite(args.period) and args.period > 0):
        raise HostError(f"--period must be a positive number of seconds, got {args.period}")
    rep = tanh_sil.cycle_report(load_params(args.params), args.period, modes, args.per_class, args.seed)
    lines = tanh_sil.cycle_text(rep)
    return publish(args, "tanh", rep, lines, f"tanh law, {args.params}")


def run_controller(args: argparse.Namespace, modes) -> int:
    """The whole controller step of Fig. 2 (host/controller_cycles.py): NN and PID paths apart."""
    from host import controller_cycles
    from host.nn_controller import flight_config, load_artifact

    a = load_artifact(args.artifact)   # None: the stand-in network fitted to the PID law
    rep = controller_cycles.cycle_report(a, flight_config(), modes, args.per_class, args.seed)
    lines = controller_cycles.cycle_text(rep)
    return publish(args, "controller", rep, lines, f"controller step, {args.artifact or 'stand-in network'}")


# Entry points the report knows: name -> handler(args, modes).
ENTRIES = {"network": run_network, "tanh": run_tanh, "controller": run_controller}


def run(args: argparse.Namespace) -> int:
    if args.per_class < 1:
        raise HostError(f"--per-class: need at least 1, got {args.per_class}")
    modes = MODES if args.mode == "all" else (args.mode,)
    return ENTRIES[args.entry](args, modes)
