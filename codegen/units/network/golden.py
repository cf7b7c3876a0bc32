"""Golden model: numpy float32 mirror of the generated network C, operation for operation.

The C computes MATLAB's mapminmax -> MLP -> reverse mapminmax with both maps folded into the layers
at generation time (fold.py: W1', b1', W2', b2', float32). Same IEEE operations in the same order as
codegen/units/network/templates/network.c.j2:
  normalise    xn[i] = x[i] - xoffset[i] for a centred input, xn[i] = x[i] for a raw one
  mlp          acc = b1'[j]; acc = acc + W1'[j][i] * xn[i] for i = 0..n_in-1; h = sg_tanhf(acc)
               y[k] = b2'[k]; y[k] = y[k] + W2'[k][j] * h[j] for j = 0..n_hidden-1;
               a NaN y[k] is the canonical NaN
  denormalise  the canonical-NaN rule alone (the reverse mapminmax is in W2', b2')
Sums run as Python loops over the summation index and are vectorised across the batch and the
neurons; never `@`, dot or sum (they reorder and may fuse). tanh is codegen.detmath.tanhf, the
numpy twin of sg_tanhf (the C computes it inline, two neurons at a time, from a signed copy of
its table: the same bits). Every stage asserts float32 (numpy 2 promotes float32 with a float64
scalar to float64).
"""
from __future__ import annotations

import numpy as np

from codegen import detmath
from codegen.artifact import Artifact
from codegen.units.network.fold import Folded, fold

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


def _normalise(f: Folded, x: np.ndarray) -> np.ndarray:
    xn = x.copy()
    with np.errstate(all="ignore"):
        for c, i in enumerate(f.centred_inputs):
            xn[:, i] = _f32(x[:, i] - f.xoffset[c], "normalise subtract")
    return _f32(xn, "normalise")


def normalise(a: Artifact, x: np.ndarray) -> np.ndarray:
    """The input stage, (N, n_in) -> (N, n_in): x - xoffset for the centred inputs, x for the raw
    ones (the rest of mapminmax is folded into W1', b1')."""
    return _normalise(fold(a), _batch(x, a.n_in, "x"))


def sequential_affine(W: np.ndarray, b: np.ndarray, v: np.ndarray, what: str) -> np.ndarray:
    """acc[:, r] = b[r], then acc + W[r][c] * v[c] for c in order — the C's accumulation order."""
    W = _f32(W, f"{what} W")
    acc = np.repeat(_f32(b, f"{what} b")[None, :], v.shape[0], axis=0)
    with np.errstate(all="ignore"):
        for c in range(W.shape[1]):
            acc = _f32(acc + _f32(W[:, c] * v[:, c, None], f"{what} W*v"), f"{what} accumulate")
    return acc


def _hidden_preactivation(f: Folded, xn: np.ndarray) -> np.ndarray:
    return sequential_affine(f.W1, f.b1, _f32(xn, "mlp input"), "hidden")


def hidden_preactivation(a: Artifact, xn: np.ndarray) -> np.ndarray:
    """b1' + W1' xn accumulated sequentially; (N, n_in) -> (N, n_hidden)."""
    return _hidden_preactivation(fold(a), _batch(xn, a.n_in, "xn"))


def tansig(acc: np.ndarray) -> np.ndarray:
    """MATLAB tansig as the flight C computes it: sg_tanhf via its numpy twin."""
    return _f32(detmath.tanhf(_f32(acc, "tansig input")), "tansig output")


def _output_layer(f: Folded, h: np.ndarray) -> np.ndarray:
    return sequential_affine(f.W2, f.b2, _f32(h, "output input"), "output")


def output_layer(a: Artifact, h: np.ndarray) -> np.ndarray:
    """b2' + W2' h accumulated sequentially (raw output units); (N, n_hidden) -> (N, n_out)."""
    return _output_layer(fold(a), _batch(h, a.n_hidden, "h"))


def _canonical(y: np.ndarray) -> np.ndarray:
    return detmath.canonf(_f32(y, "output"))


def _mlp(f: Folded, xn: np.ndarray) -> np.ndarray:
    return _canonical(_output_layer(f, tansig(_hidden_preactivation(f, xn))))


def mlp(a: Artifact, xn: np.ndarray) -> np.ndarray:
    """The folded MLP on the input stage's values, (N, n_in) -> (N, n_out) in raw output units, a
    NaN output canonical."""
    return _mlp(fold(a), _batch(xn, a.n_in, "xn"))


def denormalise(a: Artifact, yn: np.ndarray) -> np.ndarray:
    """The output stage, (N, n_out) -> (N, n_out): a NaN becomes the canonical NaN, every other value
    is kept (the reverse mapminmax is folded into W2', b2')."""
    return _canonical(_f32(_batch(yn, a.n_out, "yn"), "denormalise input"))


def network_eval(a: Artifact, x: np.ndarray) -> np.ndarray:
    """The whole network path on raw inputs, (N, n_in) float32 -> (N, n_out) float32."""
    x = _batch(x, a.n_in, "x")
    f = fold(a)
    out = np.empty((x.shape[0], a.n_out), dtype=np.float32)
    for start in range(0, x.shape[0], CHUNK_ROWS):
        rows = slice(start, start + CHUNK_ROWS)
        out[rows] = _mlp(f, _normalise(f, x[rows]))
    return out
