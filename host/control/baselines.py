"""Baselines fitted on the training split, so the report shows what the network buys.

* `LinearLS`: least squares of the torque on the 12 raw inputs plus a bias, M = W·S_in + b.
* `SaturatedLinear`: a PD law with feed-forward and saturation,
  M = clip(Kp·A_bd + Kd·ω_e + C·M_ff(ω_d, ω̇_d) + b, ±bound), M_ff = I·ω̇_d + ω_d × I·ω_d (Table 6
  inertia, rad units) the torque that flies the desired sequence. Kp, Kd, C are full 3×3
  matrices and b a bias; each axis is fitted by least squares on the training samples whose
  command on that axis is not on the bound, then clipped at the bound. With no bound it is PD +
  feed-forward fitted on every sample.

Inputs are S_in in Table 2 units (°/s, °/s², °, °/s; order of host.learn.samples.S_IN_NAMES),
outputs N·m.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from codegen import reading
from host.errors import HostError
from host.plant.spacecraft import TABLE6

# A sample counts as saturated when any axis is within this fraction of the bound: the optimiser
# leaves bound-active commands a few 1e-9 inside the bound, not exactly on it.
SATURATION_MARGIN = 1e-6


def _with_bias(F: np.ndarray) -> np.ndarray:
    return np.hstack([F, np.ones((F.shape[0], 1))])


def _least_squares(F: np.ndarray, Y: np.ndarray, what: str) -> np.ndarray:
    """Coefficients (n_features + 1, 3) of Y ≈ [F, 1]·c, or HostError if underdetermined."""
    A = _with_bias(F)
    if A.shape[0] < A.shape[1]:
        raise HostError(f"{what}: {A.shape[0]} samples cannot determine {A.shape[1]} coefficients per axis")
    coef, *_ = np.linalg.lstsq(A, Y, rcond=None)
    return coef


@dataclass(frozen=True)
class LinearLS:
    """M = [S_in, 1]·coef; coef (13, 3)."""

    coef: np.ndarray
    name: str = "linear least squares"

    @classmethod
    def fit(cls, X: np.ndarray, Y: np.ndarray) -> "LinearLS":
        return cls(_least_squares(X, Y, "linear least squares"))

    def predict(self, X: np.ndarray) -> np.ndarray:
        return _with_bias(X) @ self.coef


def feedforward_torque(X: np.ndarray, inertia: np.ndarray = TABLE6.inertia) -> np.ndarray:
    """M_ff = I·ω̇_d + ω_d × I·ω_d (N·m) from S_in in Table 2 units (°/s, °/s²)."""
    w_d = np.radians(X[:, 0:3])
    wdot_d = np.radians(X[:, 3:6])
    Iw = w_d @ inertia.T
    return wdot_d @ inertia.T + np.cross(w_d, Iw)


def pd_ff_features(X: np.ndarray) -> np.ndarray:
    """[A_bd (°), ω_e (°/s), M_ff (N·m)] per sample: the regressors of the saturated linear law."""
    return np.hstack([X[:, 6:9], X[:, 9:12], feedforward_torque(X)])


@dataclass(frozen=True)
class SaturatedLinear:
    """M = clip([A_bd, ω_e, M_ff, 1]·coef, ±bound); coef (10, 3); bound None = no clipping.
    n_fit: per axis, the training samples used (those not on the bound on that axis)."""

    coef: np.ndarray
    bound: float | None
    n_fit: tuple[int, ...]
    name: str = "saturated linear (PD + feed-forward + saturation)"

    @classmethod
    def fit(cls, X: np.ndarray, Y: np.ndarray, bound: float | None) -> "SaturatedLinear":
        F = pd_ff_features(X)
        unsaturated = np.ones(Y.shape, dtype=bool) if bound is None else np.abs(Y) < bound * (1 - SATURATION_MARGIN)
        coef = np.column_stack([
            _least_squares(F[unsaturated[:, k]], Y[unsaturated[:, k], k],
                           f"saturated linear fit, axis {k}, on the training samples off the bound")
            for k in range(Y.shape[1])])
        return cls(coef, bound, tuple(int(n) for n in unsaturated.sum(axis=0)))

    def predict(self, X: np.ndarray) -> np.ndarray:
        raw = _with_bias(pd_ff_features(X)) @ self.coef
        return raw if self.bound is None else np.clip(raw, -self.bound, self.bound)


# ----------------------------------------------------------------------------- file (to fly them)

BASELINES_FORMAT = "staregen-baselines/1"
_COEF_SHAPES = {"linear": (13, 3), "pdff": (10, 3)}


def baselines_document(linear: LinearLS, saturated: SaturatedLinear, dataset_sha256: str) -> dict:
    """Both fitted laws as JSON (floats as float.hex: the file gives back the very coefficients)."""
    def hexes(a):
        return [[float(v).hex() for v in row] for row in np.asarray(a, float)]
    return {"format": BASELINES_FORMAT, "dataset_sha256": dataset_sha256,
            "linear": {"coef": hexes(linear.coef)},
            "pdff": {"coef": hexes(saturated.coef), "bound": saturated.bound, "n_fit": list(saturated.n_fit)}}


def _coef(doc: dict, key: str, where: str) -> np.ndarray:
    try:
        rows = doc[key]["coef"]
        a = np.array([[float.fromhex(v) for v in row] for row in rows], dtype=float)
    except (KeyError, TypeError, ValueError, OverflowError):
        raise HostError(f"{where}: {key}.coef must be a list of rows of hex floats") from None
    if a.shape != _COEF_SHAPES[key] or not np.all(np.isfinite(a)):
        raise HostError(f"{where}: {key}.coef must be {_COEF_SHAPES[key]} finite values, got shape {a.shape}")
    return a


def load_baselines(path) -> tuple[LinearLS, SaturatedLinear]:
    """The two fitted laws of a baselines file (written by `staregen train` / the pipeline)."""
    where = str(path)
    try:
        doc = reading.read_json(path)    # capped, regular files only, strict JSON
    except reading.InputFileError as exc:
        raise HostError(str(exc)) from None
    if not isinstance(doc, dict) or doc.get("format") != BASELINES_FORMAT:
        raise HostError(f"{where}: not a baselines file (format {BASELINES_FORMAT})")
    linear, pdff = LinearLS(_coef(doc, "linear", where)), _coef(doc, "pdff", where)
    bound, n_fit = doc["pdff"].get("bound"), doc["pdff"].get("n_fit")
    if bound is not None and not (isinstance(bound, (int, float)) and not isinstance(bound, bool)
                                  and np.isfinite(bound) and bound > 0):
        raise HostError(f"{where}: pdff.bound must be a positive number or null")
    if not (isinstance(n_fit, list) and len(n_fit) == 3 and all(isinstance(n, int) and n >= 0 for n in n_fit)):
        raise HostError(f"{where}: pdff.n_fit must be 3 sample counts")
    return linear, SaturatedLinear(pdff, None if bound is None else float(bound), tuple(n_fit))
