"""The float64 reference of a network artifact: what the golden model's float32 result is judged
against (SPEC section 6, "golden vs the float64 reference within a stated bound").

Not a mirror of the C: exact numpy tanh and matrix products are the point here.
"""
from __future__ import annotations

import numpy as np

from codegen.artifact import Artifact


def reference_eval64(a: Artifact, x: np.ndarray) -> np.ndarray:
    """float64 reference of the same network (same float32 parameters, exact tanh, @ allowed)."""
    x64 = np.asarray(x, dtype=np.float64)
    im, om = a.input_map, a.output_map
    xn = (x64 - im.xoffset.astype(np.float64)) * im.gain.astype(np.float64) + float(im.ymin)
    h = np.tanh(xn @ a.W1.astype(np.float64).T + a.b1.astype(np.float64))
    yn = h @ a.W2.astype(np.float64).T + a.b2.astype(np.float64)
    return (yn - float(om.ymin)) / om.gain.astype(np.float64) + om.xoffset.astype(np.float64)
