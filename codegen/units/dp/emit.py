"""Discrete-point unit emitter: tables artifact -> `<name>.h` / `<name>.c` plus the math library
(for sg_crc32). A pure function of the tables, the entry name and the generator version."""
from __future__ import annotations

import math
import zlib
from pathlib import Path

import numpy as np

from codegen import GENERATOR_VERSION
from codegen.artifact import TABLE2_NAMES, TABLE2_UNITS
from codegen.cgen import c_float, check_name, comment, environment, math_sources
from codegen.units.dp.golden import Constants
from codegen.units.dp.tables import DpTables, stack_estimate

TEMPLATES = Path(__file__).with_name("templates")
DEFAULT_NAME = "dp"
# Points per block of the normal equations: 8 t's and one sum in registers (docs/discrete-point.md).
BLOCK = 8


def tables_crc32(t: DpTables) -> int:
    """zlib's CRC-32 of the C's constant tables in their order and layout (little-endian)."""
    crc = 0
    for table, dtype in ((t.X, "<f4"), (t.Y, "<f4"), (t.order, "<u2"), (t.half_widths, "<f4"), (t.inv_span, "<f4")):
        crc = zlib.crc32(np.ascontiguousarray(table, dtype=dtype).tobytes(), crc)
    return crc


def _floats(a: np.ndarray) -> list[list[str]]:
    return [[c_float(v) for v in row] for row in np.atleast_2d(a)]


def template_context(t: DpTables, name: str) -> dict:
    p = t.params
    c = Constants(t)
    return {
        "name": name, "P": name.upper(), "generator_version": GENERATOR_VERSION, "sha256": t.sha256,
        "creator": comment(t.metadata.get("creator", "")),
        "n": t.n, "s_limit": p.s_limit, "n_min": p.n_min, "iterations": p.iterations, "n_levels": t.n_levels,
        "bisect_steps": math.ceil(math.log2(t.n + 1)), "block": BLOCK,
        "r_text": f"{p.r:g}", "widen_text": f"{p.widen:g}", "ridge_text": f"{p.ridge:g}", "tukey_text": f"{p.tukey_c:g}",
        "c_scale": c_float(c.c_scale), "ridge": c_float(c.ridge),
        "stack_estimate": stack_estimate(p.s_limit), "flash_bytes": t.flash_bytes,
        "tables_crc32": f"0x{tables_crc32(t):08x}",
        "inputs": [{"index": i, "name": n, "unit": u} for i, (n, u) in enumerate(zip(TABLE2_NAMES, TABLE2_UNITS))],
        "x": _floats(t.X), "y": _floats(t.Y), "half": _floats(t.half_widths),
        "inv_span": [c_float(v) for v in t.inv_span],
        "order": [[str(int(v)) for v in row] for row in t.order],
    }


def dp_sources(t: DpTables, name: str = DEFAULT_NAME) -> dict[str, str]:
    """{file name: text} of the generated step and the math library it calls."""
    check_name(name)
    env, ctx = environment(TEMPLATES), template_context(t, name)
    sources = {f"{name}.h": env.get_template("dp.h.j2").render(ctx),
               f"{name}.c": env.get_template("dp.c.j2").render(ctx)}
    sources.update(math_sources())
    return sources
