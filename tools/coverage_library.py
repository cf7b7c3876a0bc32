"""Structural coverage of the deterministic math library (sg_math.c / sg_math.h) under its own
vectors, so that a branch no unit can reach (a NaN argument, an overflow, an exponent the unit's
constant never has) is still shown taken somewhere — and its result checked against the numpy
twin (codegen.detmath) bit for bit while it is.

Every public function and every inline helper of the header is called from a small harness that
reads (operation, a, b) records of 32-bit words on stdin and writes the result's bits. The vectors
per operation: special values (±0, subnormals, the smallest normals, ±Inf, NaNs of both signs and
payloads, ±FLT_MAX, the boundaries the library tests), every pair of them for the two-argument
functions, uniformly random bit patterns, and random finite arguments over the ranges that
matter (log-uniform magnitudes of both signs).
"""
from __future__ import annotations

import tempfile
import zlib
from dataclasses import dataclass
from functools import partial
from pathlib import Path
from typing import Callable

import numpy as np

from codegen import detmath
from codegen.cgen import math_sources
from tools.coverage import COVERAGE_FLAGS, LIBRARY, CoverageReport, compile_in, gcov_counts, report_lines, run_words
from firmware.flags import COMMON, with_opt

F32, U32 = np.float32, np.uint32
POWC_EXPONENTS = (0.8, -0.2)   # one positive and one negative constant exponent for sg_powf_const


@dataclass(frozen=True)
class Op:
    name: str
    arity: int
    call: str                                   # C expression of a.f / b.f / a.u / b.u giving a float
    twin: Callable[[np.ndarray, np.ndarray], np.ndarray]


def _unary(f: Callable[[np.ndarray], np.ndarray]) -> Callable[[np.ndarray, np.ndarray], np.ndarray]:
    def twin(a: np.ndarray, b: np.ndarray) -> np.ndarray:
        return f(a)
    return twin


def _powf_const(x: np.ndarray, t: detmath.PowC) -> np.ndarray:
    return detmath.powf_const(x, t)


OPS = (
    Op("sg_tanhf", 1, "sg_tanhf(a.f)", _unary(detmath.tanhf)),
    Op("sg_inline_tanhf", 1, "sg_inline_tanhf(a.f)", _unary(detmath.tanhf)),
    Op("sg_inline_tanhf_full", 1, "sg_inline_tanhf_full(a.f)", _unary(detmath.tanhf)),
    Op("sg_expf", 1, "sg_expf(a.f)", _unary(detmath.expf)),
    Op("sg_logf", 1, "sg_logf(a.f)", _unary(detmath.logf)),
    Op("sg_logf_tab", 1, "sg_logf_tab(a.f)", _unary(detmath.logf_tab)),
    Op("sg_sinf", 1, "sg_sinf(a.f)", _unary(detmath.sinf)),
    Op("sg_cosf", 1, "sg_cosf(a.f)", _unary(detmath.cosf)),
    Op("sg_asinf", 1, "sg_asinf(a.f)", _unary(detmath.asinf)),
    Op("sg_sqrtf", 1, "sg_sqrtf(a.f)", _unary(detmath.sqrtf)),
    Op("sg_canonf", 1, "sg_canonf(a.f)", _unary(detmath.canonf)),
    Op("sg_atan2f", 2, "sg_atan2f(a.f, b.f)", detmath.atan2f),
    Op("sg_powf_pos", 2, "sg_powf_pos(a.f, b.f)", detmath.powf_pos),
    Op("sg_powf_fused", 2, "sg_powf_fused(a.f, b.f)", detmath.powf_fused),
    Op("sg_powf_tab", 2, "sg_powf_tab(a.f, b.f)", detmath.powf_tab),
    *(Op(f"sg_powf_const[y={y}]", 1, f"cov_powf_const(a.f, &cov_powc_{k})",
         _unary(partial(_powf_const, t=detmath.powc_tables(y))))
      for k, y in enumerate(POWC_EXPONENTS)),
)
CRC_OP = len(OPS)   # sg_crc32 of the 4 bytes of a, seeded with b: checked against zlib


def _specials() -> np.ndarray:
    words = [0x00000000, 0x80000000, 0x00000001, 0x80000001, 0x007FFFFF, 0x807FFFFF, 0x00800000,
             0x80800000, 0x7F800000, 0xFF800000, 0x7FC00000, 0xFFC00000, 0x7F800001, 0xFFBFFFFF,
             0x7F7FFFFF, 0xFF7FFFFF, 0x3F800000, 0xBF800000]
    values = [2.0 ** -12, 2.0 ** -13, 9.0, 8.999999, 88.72, 88.73, -87.3, -103.9, -104.0, 0.5, 1.5,
              3.14159265, 1e-20, 1e10, 1e30, 0.7853982, 100.0, 2.0 ** -126, 2.0 ** -149]
    vals = np.array(values + [-v for v in values], dtype=F32).view(U32)
    return np.unique(np.concatenate([np.array(words, dtype=U32), vals]))


def _random_finite(rng, n: int) -> np.ndarray:
    mag = np.exp(rng.uniform(np.log(1e-8), np.log(1e4), n))
    return (mag * rng.choice([-1.0, 1.0], n)).astype(F32).view(U32)


def vectors(n: int, seed: int = 0) -> dict[str, tuple[np.ndarray, np.ndarray]]:
    """Per operation (a, b) as uint32 words: specials (and their pairs), random bits, random finite."""
    rng = np.random.default_rng(seed)
    sp = _specials()
    out = {}
    for op in OPS:
        bits = rng.integers(0, 2 ** 32, size=(2, n), dtype=np.uint64).astype(U32)
        finite = np.stack([_random_finite(rng, n), _random_finite(rng, n)])
        if op.arity == 2:
            pa, pb = (g.ravel() for g in np.meshgrid(sp, sp))
            # the two-argument power laws take exponents of moderate size; random y in (-4, 4) too
            ys = rng.uniform(-4.0, 4.0, n).astype(F32).view(U32)
            a = np.concatenate([pa, bits[0], finite[0], finite[0]])
            b = np.concatenate([pb, bits[1], finite[1], ys])
        else:
            a = np.concatenate([sp, bits[0], finite[0]])
            b = np.zeros_like(a)
        out[op.name] = (a, b)
    return out


def harness_source() -> str:
    tables = "\n".join(f"static const sg_powc_t cov_powc_{k} = "
                       f"{detmath.powc_c_initializer(detmath.powc_tables(y))};"
                       for k, y in enumerate(POWC_EXPONENTS))
    cases = "\n".join(f"        case {i}u:\n            r.f = {op.call};\n            break;"
                      for i, op in enumerate(OPS))
    return f"""/* Coverage harness of sg_math; generated by tools/coverage_library.py. */
#include <stdio.h>
#include <stdint.h>
#include "sg_math.h"

{tables}

/* one inlined copy of sg_powf_const for both exponents: each copy's exponent test takes one edge */
static float cov_powf_const(float x, const sg_powc_t *t)
{{
    return sg_powf_const(x, t);
}}

typedef union {{
    float f;
    uint32_t u;
}} cov_bits_t;

int main(void)
{{
    uint32_t rec[3];
    while (fread(rec, sizeof rec, 1u, stdin) == 1u) {{
        cov_bits_t a, b, r;
        a.u = rec[1];
        b.u = rec[2];
        switch (rec[0]) {{
{cases}
        case {CRC_OP}u:
            r.u = sg_crc32(&a.u, 4u, b.u);
            break;
        default:
            return 4;
        }}
        if (fwrite(&r.u, sizeof r.u, 1u, stdout) != 1u) {{
            return 3;
        }}
    }}
    return 0;
}}
"""


@dataclass
class LibraryResult:
    report: CoverageReport
    mismatches: dict[str, int]   # operation -> results whose bits differ from the numpy twin


def _same_bits(c: np.ndarray, twin: np.ndarray) -> np.ndarray:
    """Equal bits; two NaNs count as equal (the library's NaN payloads are not canonical: the units
    canonicalise their outputs, docs/math.md)."""
    t = np.asarray(twin, dtype=F32).view(U32)
    nan_c, nan_t = (c & U32(0x7FFFFFFF)) > U32(0x7F800000), (t & U32(0x7FFFFFFF)) > U32(0x7F800000)
    return (c == t) | (nan_c & nan_t)


def measure_library(n: int = 20_000, seed: int = 0, sources: dict[str, str] | None = None) -> LibraryResult:
    """Coverage of sg_math (or of `sources`, its files edited: tests plant faults) under n random
    words and n random finite arguments per operation, besides the specials."""
    with tempfile.TemporaryDirectory(prefix="staregen-cov-lib-") as tmp:
        folder = Path(tmp)
        files = {**(sources or math_sources()), "cov_lib.c": harness_source()}
        for name, text in files.items():
            (folder / name).write_text(text)
        objects = []
        for name in ("sg_math.c", "cov_lib.c"):
            obj = name[:-2] + ".o"
            compile_in(["gcc", *with_opt(COMMON, "-O0"), *COVERAGE_FLAGS, "-I", ".", "-c", name, "-o", obj], folder)
            objects.append(obj)
        compile_in(["gcc", *COVERAGE_FLAGS, *objects, "-o", "cov"], folder)
        vecs = vectors(n, seed)
        mismatches, total = {}, 0
        for i, op in enumerate(OPS):
            a, b = vecs[op.name]
            got = run_words(folder / "cov", _records(i, a, b))
            with np.errstate(all="ignore"):
                want = op.twin(a.view(F32), b.view(F32))
            mismatches[op.name] = int((~_same_bits(got, want)).sum())
            total += a.size
        rng = np.random.default_rng(seed + 1)
        a, b = (rng.integers(0, 2 ** 32, size=(2, 1000), dtype=np.uint64).astype(U32))
        got = run_words(folder / "cov", _records(CRC_OP, a, b))
        want = np.array([zlib.crc32(int(x).to_bytes(4, "little"), int(s)) for x, s in zip(a, b)], dtype=U32)
        mismatches["sg_crc32"] = int((got != want).sum())
        total += a.size
        files_cov, unused = gcov_counts(folder, objects, list(LIBRARY))
        return LibraryResult(CoverageReport("sg_math", total, files_cov, unused), mismatches)


def _records(op: int, a: np.ndarray, b: np.ndarray) -> bytes:
    rec = np.empty((a.size, 3), dtype=U32)
    rec[:, 0], rec[:, 1], rec[:, 2] = op, a, b
    return rec.tobytes()


def library_lines(lib: LibraryResult) -> list[str]:
    """Markdown: the library's coverage (as a unit's) and its results against the numpy twin."""
    lines = report_lines(lib.report, math_sources())
    lines[0] = (lines[0].replace("Unit `sg_math`", "Math library `sg_math` (its own vectors, every function)")
                .replace(" steps:", " calls:"))
    bad = {k: v for k, v in lib.mismatches.items() if v}
    verdict = "0 results differ" if not bad else "DIFFERING results: " + ", ".join(f"{k} {v}" for k, v in bad.items())
    return lines + [f"Results against the numpy twin (codegen.detmath; sg_crc32 against zlib), "
                    f"{len(lib.mismatches)} operations: {verdict}."]
