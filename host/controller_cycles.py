"""Cycle, memory and stack report of the whole generated controller step on the emulated Cortex-M4.

Input classes (records carry their own controller state, adapter `state_in_record`):
  nn_path     in-envelope inputs, network mode: the full step with the network
  pid_path    an attitude error beyond its Table 2 bound: the PID branch
  dwell       in-envelope inputs while the PID still flies (dwell not over)
  invalid     a NaN or Inf gyro reading: input-invalid, PID branch
  bits        random bit patterns in every field
"Our part" = the NN-path step minus the network call (controller_nn_eval, inclusive): the
desired state, preprocessing, envelope check, PID, mode logic and saturation.
"""
from __future__ import annotations

import numpy as np

from codegen import controller_spec as cs
from codegen.artifact import Artifact
from codegen.controller_emit import DEFAULT_NAME, RECORD_IN_DTYPE, STATE_DTYPE, net_name
from host import controller_gate as gate
from host.constants import DEG

BUDGET_STEP = 6_000
BUDGET_OURS = 2_500
BUDGET_FLASH = 24 * 1024
BUDGET_RAM = 1024
BUDGET_STACK = 512


def class_records(cfg: cs.ControllerConfig, per_class: int, seed: int) -> dict[str, np.ndarray]:
    """{class: (N, record bytes) uint8} for the state_in_record adapter."""
    rng = np.random.default_rng(seed)
    n = per_class
    nn_state, dwell_state = gate.random_states(rng, n, cfg.dwell_steps), gate.random_states(rng, n, cfg.dwell_steps)
    nn_state["mode"], nn_state["clean"] = 0, 0
    dwell_state["mode"], dwell_state["clean"] = 1, 0
    inside = lambda: gate.make_inputs(gate.random_geometry(rng, n), *gate.uniform_errors(rng, n, 0.95))
    A, w = gate.uniform_errors(rng, n, 3.0)
    A[:, rng.integers(0, 3)] = rng.choice([-1.0, 1.0], n) * rng.uniform(0.021, 0.06, n) * DEG   # outside
    invalid = inside()
    invalid["omega_b"][np.arange(n), rng.integers(0, 3, n)] = rng.choice(gate.SPECIAL_F32[:4], n)  # NaN / Inf
    classes = {
        "nn_path": (nn_state, inside()),
        "pid_path": (gate.random_states(rng, n, cfg.dwell_steps), gate.make_inputs(gate.random_geometry(rng, n), A, w)),
        "dwell": (dwell_state, inside()),
        "invalid": (gate.random_states(rng, n, cfg.dwell_steps), invalid),
        "bits": (gate.random_states(rng, n, cfg.dwell_steps), gate.bit_inputs(rng, n)),
    }
    out = {}
    for name, (st, inp) in classes.items():
        rec = np.zeros(n, dtype=RECORD_IN_DTYPE)
        rec["state"], rec["input"] = st, inp
        out[name] = rec.view(np.uint8).reshape(n, -1)
    return out


def cycle_report(a: Artifact, cfg: cs.ControllerConfig, modes, per_class: int, seed: int) -> dict:
    """JSON-ready report of `<name>_step`: cycles per mode and class, functions, flash/RAM/stack."""
    from host.sil import controller_arm_build
    from tools import size, stack
    from tools.cycles import profile_entry
    from tools.m4.elf import Image

    name = DEFAULT_NAME
    build = controller_arm_build(a, cfg, "state_in_record", name)
    image = Image(build.elf)
    entry_fn = f"{name}_step"
    prof = profile_entry(image, entry_fn, class_records(cfg, per_class, seed), modes)
    sz = size.sizes(build.elf, build.map)
    objs = sz.of_objects([f"{name}.o", f"{net_name(name)}.o", "sg_math.o"])
    bound = stack.worst_case(image, build.su_files, entry_fn)
    stack.check_against_paint(bound, prof.stack_painted)
    net_fn = f"{net_name(name)}_eval"
    net = prof.functions.get(net_fn, {}).get("inclusive", {})
    nn_max = prof.by_class["nn_path"]["ideal"]["max"] if "ideal" in modes else None
    ours = (nn_max - net["ideal"]["max"]) if nn_max is not None and "ideal" in net else None
    return {
        "entry_fn": entry_fn, "elf": str(build.elf), "cycles": prof.cycles, "by_class": prof.by_class,
        "network_inclusive": net, "ours_nn_path_ideal_max": ours,
        "flash_bytes": objs["flash"], "ram_bytes": objs["ram"], "state_bytes": STATE_DTYPE.itemsize,
        "stack_bytes": bound.bytes, "stack_painted": prof.stack_painted, "stack_path": bound.path,
        "newlib": build.newlib, "per_class": per_class, "functions": prof.functions,
    }


def _verdict(value, budget, unit) -> str:
    if value is None:
        return "unknown"
    return (f"within budget ({value} <= {budget} {unit})" if value <= budget
            else f"OVER budget by {value - budget} {unit}")


def cycle_text(rep: dict) -> list[str]:
    modes = list(rep["cycles"])
    lines = [f"entry controller ({rep['entry_fn']}), ELF {rep['elf']}, {rep['per_class']} vectors per class", "",
             "| class | " + " | ".join(f"{m} min / median / max" for m in modes) + " |",
             "|---|" + "---:|" * len(modes)]
    for c, row in rep["by_class"].items():
        lines.append(f"| {c} | " + " | ".join(f"{row[m]['min']} / {row[m]['median']} / {row[m]['max']}" for m in modes) + " |")
    lines += ["", "| function | calls | inclusive max (ideal) | exclusive max (ideal) |", "|---|---:|---:|---:|"]
    for fn, row in rep["functions"].items():
        if "ideal" in row["inclusive"]:
            lines.append(f"| {fn} | {row['calls']['max']} | {row['inclusive']['ideal']['max']} | "
                         f"{row['exclusive']['ideal']['max']} |")
    worst = rep["cycles"]["ideal"]["max"] if "ideal" in rep["cycles"] else None
    lines += ["",
              f"flash (controller + network + sg_math objects): {rep['flash_bytes']} B; RAM: {rep['ram_bytes']} B "
              f"static + {rep['state_bytes']} B caller-owned state; stack {rep['stack_bytes']} B static worst case via "
              f"{' -> '.join(rep['stack_path'])} (painted {rep['stack_painted']} B); newlib: {'yes' if rep['newlib'] else 'no'}",
              f"budget, whole step worst case ideal: {_verdict(worst, BUDGET_STEP, 'cycles')}",
              f"step without the network (NN path, ideal max): {rep['ours_nn_path_ideal_max']} cycles "
              f"(not a SPEC budget; the whole step's 6,000 minus the network's 3,500 is {BUDGET_OURS})",
              f"budget, flash: {_verdict(rep['flash_bytes'], BUDGET_FLASH, 'B')}",
              f"budget, RAM: {_verdict(rep['ram_bytes'] + rep['state_bytes'], BUDGET_RAM, 'B')}",
              f"budget, stack: {_verdict(rep['stack_bytes'], BUDGET_STACK, 'B')}"]
    return lines
