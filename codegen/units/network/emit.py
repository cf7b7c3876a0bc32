"""Network unit emitter: artifact -> `<name>.h` / `<name>.c` (the network path) plus the deterministic math library.

Generation is a pure function of the artifact, the entry name and the generator version: no
timestamps, no paths, no dict-order dependence, so the same artifact gives byte-identical sources.
"""
from __future__ import annotations

import os
import zlib
from pathlib import Path

import numpy as np

from codegen import GENERATOR_VERSION
from codegen.detmath import TANH_COLS, TANH_HALF, tanh_rows
from codegen.artifact import Artifact
from codegen.cgen import c_float, check_name, comment, unit_sources, write_sources
from codegen.units.network.fold import Folded, fold

TEMPLATES = Path(__file__).with_name("templates")
DEFAULT_NAME = "network"
# Neurons per MLP loop iteration. Four would save ~11 cycles (12-40-3, ideal) but the loop, with
# tanh inlined, then outgrows the STM32F4 ART's 1 KB instruction cache: 8,410 cycles instead of
# 5,165 with 5 wait states (BENCHMARKS.md, issue 4).
UNROLL_CHOICES = (2, 1)
# Most weights of one neuron loaded back to back before their sum: 13 (bias + 12 inputs) keeps
# the 12 inputs, 3 output sums and the group within the FPU registers of the Cortex-M4.
LOAD_GROUP = 13


def _labels(names, units, descriptions, lows=None, highs=None) -> list[dict]:
    rows = []
    for i, (n, u, d) in enumerate(zip(names, units, descriptions)):
        row = {"index": i, "name": comment(n), "unit": comment(u), "description": comment(d)}
        if lows is not None:
            row.update(min=f"{float(lows[i]):.9g}", max=f"{float(highs[i]):.9g}")
        rows.append(row)
    return rows


def _neurons(f: Folded) -> list[dict]:
    """Per hidden neuron, the folded constants in the order the MLP loop consumes them."""
    return [
        {"bias": c_float(f.b1[j]),
         "w_in": [c_float(w) for w in f.W1[j]],
         "w_out": [c_float(w) for w in f.W2[:, j]]}
        for j in range(f.W1.shape[0])
    ]


def hidden_unroll(n_hidden: int) -> int:
    """Neurons per MLP loop iteration: the largest of UNROLL_CHOICES dividing n_hidden (no remainder loop)."""
    return next(u for u in UNROLL_CHOICES if n_hidden % u == 0)


def load_groups(n_in: int) -> list[list[int]]:
    """A hidden neuron's input weights in consumption order (0 = bias, i = W1[j][i-1]), cut into
    groups of at most LOAD_GROUP that the C loads back to back before summing them."""
    order = list(range(n_in + 1))
    return [order[k:k + LOAD_GROUP] for k in range(0, len(order), LOAD_GROUP)]


# FPU registers the input stage may use without saving any (s0-s15, AAPCS caller-saved).
CALLER_SAVED_S = 16


def input_chunks(centred) -> list[list[dict]]:
    """The inputs in order, cut into groups loaded back to back: {"i": input, "c": its index in
    <name>_in_xoffset or None for a raw input}. A group's loads (one register per raw input, two
    per centred one: x and its offset) sit beside the inputs already done, within CALLER_SAVED_S
    registers; the fewer the groups, the fewer the load runs (each costs a cycle)."""
    rows, c = [], 0
    for i, is_centred in enumerate(centred):
        rows.append({"i": i, "c": c if is_centred else None})
        c += bool(is_centred)
    chunks, done = [], 0
    while done < len(rows):
        regs, size = done, 0
        while done + size < len(rows) and regs + (1 if rows[done + size]["c"] is None else 2) <= CALLER_SAVED_S:
            regs += 1 if rows[done + size]["c"] is None else 2
            size += 1
        size = max(size, 1)
        chunks.append(rows[done:done + size])
        done += size
    return chunks


def tables_crc32(a: Artifact) -> int:
    """zlib's CRC-32 of the network's constant tables in the C's order and layout (little-endian
    float32): the folded neurons, b2', the offsets of the centred inputs (if any), then the signed
    tanh table (the path's tanh: it no longer reads sg_math's sg_tanh_tab): what
    <name>_tables_crc32() computes on the target."""
    f = fold(a)
    neurons = np.concatenate([f.b1[:, None], f.W1, f.W2.T], axis=1)
    tables = [neurons, f.b2] + ([f.xoffset] if f.centred_inputs else []) + [tanh_rows()]
    crc = 0
    for table in tables:
        crc = zlib.crc32(np.ascontiguousarray(table, dtype="<f4").tobytes(), crc)
    return crc


def template_context(a: Artifact, name: str) -> dict:
    env, out = a.envelope, a.outputs
    f = fold(a)
    return {
        "unroll": hidden_unroll(a.n_hidden), "stride": 1 + a.n_in + a.n_out,
        "load_groups": load_groups(a.n_in), "input_chunks": input_chunks(f.centred),
        "name": name, "P": name.upper(),
        "n_in": a.n_in, "n_hidden": a.n_hidden, "n_out": a.n_out,
        "sha256": a.sha256, "generator_version": GENERATOR_VERSION,
        "creator": comment(a.metadata.get("creator", "")),
        "envelope_source": comment(env.source),
        "inputs": _labels(env.names, env.units, env.descriptions, env.min, env.max),
        "outputs": _labels(out.names, out.units, out.descriptions),
        "input_modes": [{"index": i, "mode": "centred" if c else "raw", "ratio": f"{r:.6g}"}
                        for i, (c, r) in enumerate(zip(f.centred, f.ratio))],
        "neurons": _neurons(f),
        "tanh_rows": [[c_float(v) for v in row] for row in tanh_rows()],
        "tanh_half": TANH_HALF, "tanh_cols": TANH_COLS,
        "tables_crc32": f"0x{tables_crc32(a):08x}",
        "b2": [c_float(v) for v in f.b2],
        "centred": f.centred_inputs,
        "in_xoffset": [c_float(v) for v in f.xoffset],
    }


def network_sources(a: Artifact, name: str = DEFAULT_NAME) -> dict[str, str]:
    """{file name: text} of the generated network path and the math library it calls."""
    check_name(name)
    return unit_sources(TEMPLATES, "network", name, template_context(a, name))


def emit(a: Artifact, out_dir: str | os.PathLike, name: str = DEFAULT_NAME) -> list[Path]:
    """Generate and write `<name>.h`, `<name>.c`, `sg_math.h`, `sg_math.c` into out_dir."""
    return write_sources(network_sources(a, name), out_dir)
