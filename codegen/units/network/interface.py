"""The network unit's interface for the ICD: its two arrays, element by element from the artifact
(names, units, descriptions and the input envelope of paper 001 Table 2 or the artifact's own),
the output bound computed from the weights. Stateless: no state, no status word. The texts come
from the artifact file: the ICD escapes them for its tables."""
from __future__ import annotations

import numpy as np

from codegen.artifact import Artifact
from codegen.unit import FieldDoc, StatusBit

CANON_NAN = "0x7FC00000"


def f32(x) -> str:
    """The shortest decimal that reads back as the same float32."""
    return str(np.float32(x))


def grouped_units(prefix: str, units: tuple[str, ...]) -> str:
    """'x[0..2] deg/s, x[3..5] deg/s^2': the element units, runs of equal units merged."""
    parts, start = [], 0
    for i in range(1, len(units) + 1):
        if i == len(units) or units[i] != units[start]:
            idx = f"{start}" if i - 1 == start else f"{start}..{i - 1}"
            parts.append(f"{prefix}[{idx}] {units[start]}")
            start = i
    return ", ".join(parts)


def output_bounds(a: Artifact) -> tuple[np.ndarray, np.ndarray]:
    """Per output, [lo, hi] that y can reach for any input that does not produce NaN: the hidden
    tansig is in [-1, 1], so |yn_k| <= |b2_k| + sum_j |W2_kj|, mapped back through the output
    mapminmax (float64, before float32 rounding)."""
    w2, b2 = np.asarray(a.W2, dtype=np.float64), np.asarray(a.b2, dtype=np.float64)
    reach = np.abs(b2) + np.abs(w2).sum(axis=1)
    om = a.output_map
    gain, xoff, ymin = (np.asarray(om.gain, dtype=np.float64), np.asarray(om.xoffset, dtype=np.float64),
                        float(om.ymin))
    ends = [(yn - ymin) / gain + xoff for yn in (b2 - reach, b2 + reach)]
    return np.minimum(*ends), np.maximum(*ends)


def field_docs(a: Artifact) -> dict[str, list[FieldDoc]]:
    env, out = a.envelope, a.outputs
    lo, hi = output_bounds(a)
    envelope = "; ".join(f"x[{i}] [{f32(mn)}, {f32(mx)}]" for i, (mn, mx) in enumerate(zip(env.min, env.max)))
    inputs = "; ".join(f"x[{i}] {n}: {d}" for i, (n, d) in enumerate(zip(env.names, env.descriptions)))
    outputs = "; ".join(f"y[{k}] {n}: {d}" for k, (n, d) in enumerate(zip(out.names, out.descriptions)))
    reach = "; ".join(f"y[{k}] [{lo[k]:.6g}, {hi[k]:.6g}]" for k in range(len(lo)))
    return {
        "input": [FieldDoc("x", grouped_units("x", env.units), "per element (meaning)",
                           f"trained envelope ({env.source}): {envelope}; outside it evaluated all the same "
                           "(no check, no status: the caller checks the envelope, as the controller does)",
                           inputs)],
        "output": [FieldDoc("y", grouped_units("y", out.units), "per element (meaning)",
                            f"bounded by the weights (tansig in [-1, 1]): {reach}, up to float32 rounding; the "
                            f"canonical NaN {CANON_NAN} when an input is NaN or so large that a sum overflows",
                            outputs)],
    }


def status_bits() -> list[StatusBit]:
    """None: the network path has no status word (a NaN output is its only signal)."""
    return []
