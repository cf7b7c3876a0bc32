"""Discrete-point unit emitter: tables artifact -> `<name>.h` / `<name>.c` plus the math library
(for sg_crc32). A pure function of the tables, the entry name and the generator version."""
from __future__ import annotations

import math
import zlib
from pathlib import Path

import numpy as np

from codegen import GENERATOR_VERSION
from codegen.artifact import TABLE2_NAMES, TABLE2_UNITS
from codegen.cgen import c_float, check_name, comment, unit_sources
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


F32_MAX = float(np.finfo(np.float32).max)


def _ulp32(r: float) -> float:
    """The float32 spacing in the binade of r > 0 (2^(e - 23) for r in [2^e, 2^(e + 1)), 2^-149
    among the subnormals): at least the spacing at every |z| <= r, and the step from r's binade up."""
    if not r > 0.0:
        return 2.0 ** -149
    return max(math.ldexp(1.0, math.frexp(r)[1] - 24), 2.0 ** -149)


def window_counts(t: DpTables) -> np.ndarray:
    """(levels, 12) int: W[l][k] >= cnt[k] of the C at level l for every input q.

    The C counts the samples of input k with a <= x <= b, a = fl(q - h), b = fl(q + h) (float32,
    h = half[l][k]; q is finite: the step turns non-finite inputs away first). Proof that any two
    counted values differ by at most 2h + 2 u, u = ulp32(M + 2h), M = max |x_k|: b >= x >= -M
    forces q + h >= -M - ulp32(M) (a real value below that rounds to at most -M - ulp32(M), the
    float next below -M), and a <= M forces q - h <= M + ulp32(M); so |q -+ h| <= R = M + 2h +
    ulp32(M) <= 2 (M + 2h). While 2 (M + 2h) < FLT_MAX neither rounding overflows and each is
    off by at most ulp32(R) / 2 <= u, so b - a <= 2h + 2u. W is the most sorted values of input k
    in one closed window [x_i, x_i + w] (start it at the smallest value counted), counted in
    float64 with u taken at the float64 value above the computed M + 2h (so never below the true
    u) and w = 2h (1 + 2^-20) + 4u: the 2u to spare dwarf the float64 rounding of x_i + w (under
    2^-52 (M + 2h + 4u); u >= 2^-24 (M + 2h)). Where 2 (M + 2h) >= FLT_MAX (no such tables in
    practice) W is N."""
    n, levels = t.n, t.half_widths.shape[0]
    out = np.full((levels, t.X.shape[1]), n, dtype=np.int64)
    for k in range(t.X.shape[1]):
        v = np.sort(t.X[:, k].astype(np.float64))
        big = float(np.max(np.abs(v)))
        for lv in range(levels):
            h = float(t.half_widths[lv, k])
            if not 2.0 * (big + 2.0 * h) < F32_MAX:
                continue
            u = _ulp32(float(np.nextafter(big + 2.0 * h, np.inf)))
            w = 2.0 * h * (1.0 + 2.0 ** -20) + 4.0 * u
            out[lv, k] = int(np.max(np.searchsorted(v, v + w, side="right") - np.arange(n)))
    return out


def loop_bounds(t: DpTables) -> dict[str, int]:
    """The data-dependent `wcet: loop bound N` of the C (N: the most iterations of the loop's
    body per entry into the loop, for every input):
      scan_bound   the candidate scan `for (j = first[kb]; j < end; ++j)` of the level stage runs
                   cnt[kb] = min_k cnt[k] <= min_k W[l][k] times (`window_counts`) at level l; the
                   loop is entered once per level and carries one number, the max over levels,
                   and at most N (cnt counts positions of [0, N]).
      m_bound      the loops over the m points used: m = min(found, S_limit), found <= N (the hits
                   of one scan, at most its candidates, or every sample).
      block_bound  the blocks of the normal equations, p0 = 0, BLOCK, ... < m: ceil(m_bound / BLOCK).
    The other loops have constant trip counts (12 inputs, 13 parameters, triangles counted as full
    rows of 13, N levels, N samples, ceil(log2(N + 1)) bisection steps, the IRLS iterations)."""
    scan = int(np.max(np.min(window_counts(t), axis=1)))
    m = min(t.params.s_limit, t.n)
    return {"scan_bound": min(scan, t.n), "m_bound": m, "block_bound": -(-m // BLOCK)}


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
        **loop_bounds(t),
    }


def dp_sources(t: DpTables, name: str = DEFAULT_NAME) -> dict[str, str]:
    """{file name: text} of the generated step and the math library it calls."""
    check_name(name)
    return unit_sources(TEMPLATES, "dp", name, template_context(t, name))
