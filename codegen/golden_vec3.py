"""float32 3-vectors of the golden models: the C's vec3 helpers (codegen/templates/vec3.c.j2)
operation for operation. A vec3 is a tuple of three float32 arrays (or numpy float32 scalars);
every result is checked to be float32, so a stray float64 cannot creep into a golden model."""
from __future__ import annotations

import numpy as np

F32 = np.float32


def f32(a, what: str = "vec3"):
    """a, asserted float32 (the golden models' guard against silent promotion)."""
    assert a.dtype == F32, f"golden {what}: expected float32, got {a.dtype}"
    return a


def v3(*parts):
    return tuple(f32(p) for p in parts)


def v_add(a, b):
    return v3(a[0] + b[0], a[1] + b[1], a[2] + b[2])


def v_sub(a, b):
    return v3(a[0] - b[0], a[1] - b[1], a[2] - b[2])


def v_scale(a, s):
    return v3(a[0] * s, a[1] * s, a[2] * s)


def v_dot(a, b):
    return f32((a[0] * b[0] + a[1] * b[1]) + a[2] * b[2], "dot")


def v_cross(a, b):
    return v3(a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])
