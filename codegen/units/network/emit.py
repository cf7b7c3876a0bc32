"""Network unit emitter: artifact -> `<name>.h` / `<name>.c` (the network path) plus the deterministic math library.

Generation is a pure function of the artifact, the entry name and the generator version: no
timestamps, no paths, no dict-order dependence, so the same artifact gives byte-identical sources.
"""
from __future__ import annotations

import os
import zlib
from pathlib import Path

import numpy as np

from codegen import GENERATOR_VERSION, detmath
from codegen.artifact import Artifact
from codegen.cgen import c_float, check_name, comment, environment, math_sources, write_sources

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


def _neurons(a: Artifact) -> list[dict]:
    """Per hidden neuron, the constants in the order the MLP loop consumes them."""
    return [
        {"bias": c_float(a.b1[j]),
         "w_in": [c_float(w) for w in a.W1[j]],
         "w_out": [c_float(w) for w in a.W2[:, j]]}
        for j in range(a.n_hidden)
    ]


def hidden_unroll(n_hidden: int) -> int:
    """Neurons per MLP loop iteration: the largest of UNROLL_CHOICES dividing n_hidden (no remainder loop)."""
    return next(u for u in UNROLL_CHOICES if n_hidden % u == 0)


def load_groups(n_in: int) -> list[list[int]]:
    """A hidden neuron's input weights in consumption order (0 = bias, i = W1[j][i-1]), cut into
    groups of at most LOAD_GROUP that the C loads back to back before summing them."""
    order = list(range(n_in + 1))
    return [order[k:k + LOAD_GROUP] for k in range(0, len(order), LOAD_GROUP)]


# <name>_tanh_rows (network.c): sg_tanh_tab with the sign of the argument folded in, for tansig
# without |x| and without a final negation. Each half has TANH_HALF rows of TANH_COLS floats (a
# power of two: a row's address is one shift and add): sg_tanh_tab's 121 intervals, then rows that
# give exactly 1 for 9 <= |x| < 16 (c0 = 1, the rest 0), so that one compare of the two indices of a
# pair, OR-ed, tells whether both are in the table. For x < 0 the row of interval i is mirrored
# below the middle (row TANH_HALF - 1 - i) with the signs below: t = x + c = -(|x| - c) and a Horner
# chain whose every intermediate is sg_tanhf's or its exact negation, so -sg_tanhf(|x|) bit for bit.
TANH_HALF = 128
TANH_COLS = 8
TANH_MIRROR_SIGNS = np.array([-1, -1, 1, -1, 1, -1], dtype=np.float32)


def tanh_rows() -> np.ndarray:
    """<name>_tanh_rows, (2 * TANH_HALF, TANH_COLS) float32: for x < 0 the mirrored rows (interval
    TANH_HALF - 1 first), then for x >= 0 sg_tanh_tab's rows, padded with zero columns."""
    tab = detmath.TANH_TABLE
    pos = np.zeros((TANH_HALF, TANH_COLS), dtype=np.float32)
    pos[:tab.shape[0], :6] = tab
    pos[tab.shape[0]:, 1] = 1.0  # tanh is 1 to float32 precision from 9 on (sg_tanhf's rule)
    neg = pos.copy()
    neg[:, :6] *= TANH_MIRROR_SIGNS
    return np.concatenate([neg[::-1], pos]).astype(np.float32)


# FPU registers the normalisation may use without saving any (s0-s15, AAPCS caller-saved).
CALLER_SAVED_S = 16


def normalise_chunks(n_in: int) -> list[list[int]]:
    """Inputs normalised together: each chunk's x, offsets and gains (3 registers per input) are
    loaded as one group beside the inputs already done, within CALLER_SAVED_S registers; the
    fewer the chunks, the fewer the load groups (each costs a cycle)."""
    chunks, done = [], 0
    while done < n_in:
        size = max(1, min(n_in - done, (CALLER_SAVED_S - done) // 3))
        chunks.append(list(range(done, done + size)))
        done += size
    return chunks


def tables_crc32(a: Artifact) -> int:
    """zlib's CRC-32 of the network's constant tables in the C's order and layout (little-endian
    float32), the signed tanh table (the path's tanh: it no longer reads sg_math's sg_tanh_tab)
    last: what <name>_tables_crc32() computes on the target."""
    neurons = np.concatenate([a.b1[:, None], a.W1, a.W2.T], axis=1)
    crc = 0
    for table in (neurons, a.b2, a.input_map.xoffset, a.input_map.gain, a.output_map.xoffset, a.output_map.gain,
                  tanh_rows()):
        crc = zlib.crc32(np.ascontiguousarray(table, dtype="<f4").tobytes(), crc)
    return crc


def template_context(a: Artifact, name: str) -> dict:
    env, out = a.envelope, a.outputs
    return {
        "unroll": hidden_unroll(a.n_hidden), "stride": 1 + a.n_in + a.n_out,
        "load_groups": load_groups(a.n_in), "normalise_chunks": normalise_chunks(a.n_in),
        "name": name, "P": name.upper(),
        "n_in": a.n_in, "n_hidden": a.n_hidden, "n_out": a.n_out,
        "sha256": a.sha256, "generator_version": GENERATOR_VERSION,
        "creator": comment(a.metadata.get("creator", "")),
        "envelope_source": comment(env.source),
        "inputs": _labels(env.names, env.units, env.descriptions, env.min, env.max),
        "outputs": _labels(out.names, out.units, out.descriptions),
        "neurons": _neurons(a),
        "tanh_rows": [[c_float(v) for v in row] for row in tanh_rows()],
        "tanh_half": TANH_HALF, "tanh_cols": TANH_COLS,
        "tables_crc32": f"0x{tables_crc32(a):08x}",
        "b2": [c_float(v) for v in a.b2],
        "in_xoffset": [c_float(v) for v in a.input_map.xoffset],
        "in_gain": [c_float(v) for v in a.input_map.gain],
        "in_ymin": c_float(a.input_map.ymin),
        "out_xoffset": [c_float(v) for v in a.output_map.xoffset],
        "out_gain": [c_float(v) for v in a.output_map.gain],
        "out_ymin": c_float(a.output_map.ymin),
    }


def network_sources(a: Artifact, name: str = DEFAULT_NAME) -> dict[str, str]:
    """{file name: text} of the generated network path and the math library it calls."""
    check_name(name)
    env, ctx = environment(TEMPLATES), template_context(a, name)
    sources = {
        f"{name}.h": env.get_template("network.h.j2").render(ctx),
        f"{name}.c": env.get_template("network.c.j2").render(ctx),
    }
    sources.update(math_sources())
    return sources


def emit(a: Artifact, out_dir: str | os.PathLike, name: str = DEFAULT_NAME) -> list[Path]:
    """Generate and write `<name>.h`, `<name>.c`, `sg_math.h`, `sg_math.c` into out_dir."""
    return write_sources(network_sources(a, name), out_dir)
