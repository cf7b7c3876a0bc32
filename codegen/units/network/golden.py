"""Golden model: numpy float32 mirror of the generated network C, operation for operation.

Same IEEE operations in the same order as codegen/templates/network.c.j2:
  normalise    xn = (x - xoffset) * gain + ymin
  mlp          acc = b1[j]; acc = acc + W1[j][i] * xn[i] for i = 0..n_in-1; h = sg_tanhf(acc)
               yn[k] = b2[k]; yn[k] = yn[k] + W2[k][j] * h[j] for j = 0..n_hidden-1
  denormalise  y = (yn - ymin) / gain + xoffset
Sums run as Python loops over the summation index and are vectorised across the batch and the
neurons; never `@`, dot or sum (they reorder and may fuse). tanh is codegen.detmath.tanhf, the
numpy twin of sg_tanhf (the C computes it inline, two neurons at a time, from a signed copy of
its table: the same bits). Every stage
asserts float32 (numpy 2 promotes float32 with a float64 scalar to float64).
"""
from __future__ import annotations

import numpy as np

from codegen import detmath
from codegen.artifact import Artifact

# Rows evaluated at once: bounds the (rows, n_hidden) temporaries to a few MB.
CHUNK_ROWS = 1 << 15


def _f32(arr: np.ndarray, stage: str) -> np.ndarray:
    assert arr.dtype == np.float32, f"golden {stage}: expected float32, got {arr.dtype}"
    return arr


def _batch(x: np.ndarray, n: int, what: str) -> np.ndarray:
    x = np.asarray(x)
    if x.dtype != np.float32 or x.ndim != 2 or x.shape[1] != n:
        raise ValueError(f"golden: {what} must be float32 of shape (N, {n}), got {x.dtype} {x.shape}")
    return x


def normalise(a: Artifact, x: np.ndarray) -> np.ndarray:
    """mapminmax of the inputs, (N, n_in) -> (N, n_in)."""
    m = a.input_map
    x = _batch(x, a.n_in, "x")
    with np.errstate(all="ignore"):
        shifted = _f32(x - _f32(m.xoffset, "xoffset"), "normalise subtract")
        scaled = _f32(shifted * _f32(m.gain, "gain"), "normalise multiply")
        return _f32(scaled + np.float32(m.ymin), "normalise add")


def sequential_affine(W: np.ndarray, b: np.ndarray, v: np.ndarray, what: str) -> np.ndarray:
    """acc[:, r] = b[r], then acc + W[r][c] * v[c] for c in order — the C's accumulation order."""
    W = _f32(W, f"{what} W")
    acc = np.repeat(_f32(b, f"{what} b")[None, :], v.shape[0], axis=0)
    with np.errstate(all="ignore"):
        for c in range(W.shape[1]):
            acc = _f32(acc + _f32(W[:, c] * v[:, c, None], f"{what} W*v"), f"{what} accumulate")
    return acc


def hidden_preactivation(a: Artifact, xn: np.ndarray) -> np.ndarray:
    """b1 + W1 xn accumulated sequentially; (N, n_in) -> (N, n_hidden)."""
    return sequential_affine(a.W1, a.b1, _f32(_batch(xn, a.n_in, "xn"), "mlp input"), "hidden")


def tansig(acc: np.ndarray) -> np.ndarray:
    """MATLAB tansig as the flight C computes it: sg_tanhf via its numpy twin."""
    return _f32(detmath.tanhf(_f32(acc, "tansig input")), "tansig output")


def output_layer(a: Artifact, h: np.ndarray) -> np.ndarray:
    """b2 + W2 h accumulated sequentially; (N, n_hidden) -> (N, n_out)."""
    return sequential_affine(a.W2, a.b2, _f32(_batch(h, a.n_hidden, "h"), "output input"), "output")


def mlp(a: Artifact, xn: np.ndarray) -> np.ndarray:
    """The MLP on normalised values, (N, n_in) -> (N, n_out)."""
    return output_layer(a, tansig(hidden_preactivation(a, xn)))


def denormalise(a: Artifact, yn: np.ndarray) -> np.ndarray:
    """Reverse mapminmax of the outputs (MATLAB's formula, a true division), (N, n_out) -> (N, n_out)."""
    m = a.output_map
    yn = _f32(_batch(yn, a.n_out, "yn"), "denormalise input")
    with np.errstate(all="ignore"):
        shifted = _f32(yn - np.float32(m.ymin), "denormalise subtract")
        scaled = _f32(shifted / _f32(m.gain, "gain"), "denormalise divide")
        return detmath.canonf(_f32(scaled + _f32(m.xoffset, "xoffset"), "denormalise add"))


def network_eval(a: Artifact, x: np.ndarray) -> np.ndarray:
    """The whole network path on raw inputs, (N, n_in) float32 -> (N, n_out) float32."""
    x = _batch(x, a.n_in, "x")
    out = np.empty((x.shape[0], a.n_out), dtype=np.float32)
    for start in range(0, x.shape[0], CHUNK_ROWS):
        rows = slice(start, start + CHUNK_ROWS)
        out[rows] = denormalise(a, mlp(a, normalise(a, x[rows])))
    return out
