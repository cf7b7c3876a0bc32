"""mapminmax folded into the network's layers, at generation time.

The artifact describes MATLAB's path: xn = (x - in_xoffset) * in_gain + in_ymin, an MLP on xn, and
y = (yn - out_ymin) / out_gain + out_xoffset. The flight C computes the same function with the two
affine maps folded into the layers, so that at run time only a subtraction per input (some inputs:
none) is left of normalisation and nothing of denormalisation:

  input side   W1'[j][i] = W1[j][i] * in_gain[i]
               b1'[j]    = b1[j] + in_ymin * sum_i W1[j][i]
               the network then reads v[i] = x[i] - in_xoffset[i] ("centred" inputs). For an input
               whose training range is not far from symmetric about 0 (RAW_MAX_RATIO), the offset is
               folded too: b1''[j] = b1'[j] - sum_{i raw} W1'[j][i] * in_xoffset[i] (W1' the float32
               weights the C multiplies by), and v[i] = x[i] ("raw" inputs).
  output side  W2'[k][j] = W2[k][j] / out_gain[k]
               b2'[k]    = (b2[k] - out_ymin) / out_gain[k] + out_xoffset[k]
               so y[k] = b2'[k] + sum_j W2'[k][j] h[j] directly.

Every folded constant is computed in float64 from the artifact's float32 values (sums with
math.fsum: correctly rounded, independent of order) and rounded once to float32. The golden model
and the emitter both take their constants from here; the float64 reference (reference.py) keeps
MATLAB's unfolded formulas, which is what the folding is checked against.

Why a raw input loses nothing: with r = max(|xmin|, |xmax|) / (xmax - xmin) <= 1, |x| <= xmax - xmin
inside the training range, so the term W1'[j][i] x[i] is no larger than W1'[j][i] (x[i] - xoffset[i])
can be (xoffset = xmin): no bits cancel between the bias and the terms that the centred form would
have kept. An input whose range lies far from 0 (r > 1: e.g. [3.789, 3.796]) keeps its subtraction,
exact or nearly so (Sterbenz) inside the range.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from codegen.artifact import Artifact
from codegen.errors import CodegenError

# An input whose range has max(|xmin|, |xmax|) / (xmax - xmin) at most this is read raw (its offset
# folded into b1); above it, or with an empty range, it stays centred (x - xoffset at run time).
RAW_MAX_RATIO = 1.0


@dataclass(frozen=True)
class Folded:
    """The constants the flight C reads (float32), and the per-input choice."""
    W1: np.ndarray          # (n_hidden, n_in): W1 * in_gain
    b1: np.ndarray          # (n_hidden,): b1 + in_ymin * sum W1 - sum over raw inputs of W1' xoffset
    W2: np.ndarray          # (n_out, n_hidden): W2 / out_gain
    b2: np.ndarray          # (n_out,): (b2 - out_ymin) / out_gain + out_xoffset
    centred: tuple          # per input: True when the C computes x[i] - xoffset[i]
    xoffset: np.ndarray     # (n_centred,): in_xoffset of the centred inputs, in input order
    ratio: np.ndarray       # per input: max(|xmin|, |xmax|) / (xmax - xmin) (inf for an empty range)

    @property
    def centred_inputs(self) -> list[int]:
        return [i for i, c in enumerate(self.centred) if c]


def range_ratio(xmin, xmax) -> np.ndarray:
    """max(|xmin|, |xmax|) / (xmax - xmin) per input, float64; inf where the range is empty."""
    lo, hi = np.asarray(xmin, dtype=np.float64), np.asarray(xmax, dtype=np.float64)
    span = hi - lo
    with np.errstate(divide="ignore", invalid="ignore"):
        r = np.maximum(np.abs(lo), np.abs(hi)) / span
    return np.where((span > 0) & np.isfinite(r), r, np.inf)


def _f32(values, what: str) -> np.ndarray:
    with np.errstate(over="ignore"):  # an overflow is reported below, as one line
        out = np.asarray(values, dtype=np.float64).astype(np.float32)
    if not np.all(np.isfinite(out)):
        raise CodegenError(f"folding mapminmax into the layers: {what} is not finite in float32")
    return out


def fold(a: Artifact) -> Folded:
    """The folded constants of artifact a (deterministic: a pure function of its float32 values)."""
    im, om = a.input_map, a.output_map
    W1 = np.asarray(a.W1, dtype=np.float64)
    b1 = np.asarray(a.b1, dtype=np.float64)
    W2 = np.asarray(a.W2, dtype=np.float64)
    b2 = np.asarray(a.b2, dtype=np.float64)
    in_gain = np.asarray(im.gain, dtype=np.float64)
    in_xoff = np.asarray(im.xoffset, dtype=np.float64)
    in_ymin = float(im.ymin)
    out_gain = np.asarray(om.gain, dtype=np.float64)
    out_xoff = np.asarray(om.xoffset, dtype=np.float64)
    out_ymin = float(om.ymin)

    ratio = range_ratio(im.xmin, im.xmax)
    centred = tuple(bool(r > RAW_MAX_RATIO) for r in ratio)
    raw = [i for i, c in enumerate(centred) if not c]

    w1 = _f32(W1 * in_gain[None, :], "W1 * in_gain")
    w1_64 = w1.astype(np.float64)
    bias1 = [math.fsum([b1[j], *(in_ymin * W1[j, i] for i in range(a.n_in)),
                        *(-(w1_64[j, i] * in_xoff[i]) for i in raw)])
             for j in range(a.n_hidden)]
    w2 = _f32(W2 / out_gain[:, None], "W2 / out_gain")
    bias2 = (b2 - out_ymin) / out_gain + out_xoff
    return Folded(W1=w1, b1=_f32(bias1, "b1"), W2=w2, b2=_f32(bias2, "b2"), centred=centred,
                  xoffset=np.asarray(im.xoffset, dtype=np.float32)[[i for i, c in enumerate(centred) if c]],
                  ratio=ratio)
