"""Staring performance (paper 001 eq. 6-8, 25-27).

Units: angles in DEGREES and rates in DEG/S, as the paper's numbers imply (Table 8: J_A = 3.96e-4
and J_ω = 4.23e-5 /s are sub-arcsecond-level figures only in degrees; in radians they would be
23 arcmin of mean pointing error, far beyond a 3″ star sensor). Inputs are taken in SI (rad,
rad/s) and converted here.

Imaging plan (the paper gives no numbers; stated here): T_img = 1 s, images taken back to back
from t_first = 10 s (after the x-axis PID settling time of ~10 s, Table 10) to the end of the run:
t_img_i = t_first + (i − ½)·T_img, i = 1 … m, m = ⌊(t_end − t_first)/T_img⌋, window i is
[t_img_i − T_img/2, t_img_i + T_img/2] and holds p + 1 samples (both ends, so a sample on the
boundary of two windows counts in both, exactly as eq. 6-7 sum them).

    J_A = 1/(3m(p+1)) Σ_i Σ_j Σ_k |A_e(j,k)|,   J_ω likewise with ω_e,   J = k1·J_A + k2·J_ω,
k1 = 1, k2 = 5; averages over targets: J̄ = mean of J_i (eq. 25-27).
"""
from __future__ import annotations

from dataclasses import asdict, dataclass
from typing import Sequence

import numpy as np

from host.core.constants import DEG
from host.errors import HostError

K1, K2 = 1.0, 5.0


@dataclass(frozen=True)
class ImagingPlan:
    T_img: float = 1.0      # s, imaging interval = window length
    t_first: float = 10.0   # s, start of the first window

    def windows(self, t_end: float) -> np.ndarray:
        """(m, 2) window bounds [start, end] inside [t_first, t_end] (with a tiny tolerance)."""
        m = int(np.floor((t_end - self.t_first) / self.T_img + 1e-9))
        if m < 1:
            raise HostError(f"no imaging window fits: the run ends at {t_end:g} s, the first "
                            f"{self.T_img:g} s window starts at {self.t_first:g} s")
        starts = self.t_first + self.T_img * np.arange(m)
        return np.stack([starts, starts + self.T_img], -1)

    def imaging_instants(self, t_end: float) -> np.ndarray:
        return self.windows(t_end).mean(-1)


DEFAULT_PLAN = ImagingPlan()


@dataclass(frozen=True)
class StaringMetrics:
    J_A: float        # deg
    J_w: float        # deg/s
    J: float          # k1·J_A + k2·J_w
    m: int = 0        # number of images (0 for an average over targets)
    p: int = 0        # simulation steps per window

    def as_dict(self) -> dict:
        return asdict(self)


def window_samples(t: np.ndarray, windows: np.ndarray) -> list[np.ndarray]:
    """Indices of the samples in each closed window, with a 1e-9 s tolerance on the ends."""
    lo = np.searchsorted(t, windows[:, 0] - 1e-9, side="left")
    hi = np.searchsorted(t, windows[:, 1] + 1e-9, side="right")
    return [np.arange(a, b) for a, b in zip(lo, hi)]


def staring_metrics(t, A_e, omega_e, plan: ImagingPlan = DEFAULT_PLAN, k1: float = K1,
                    k2: float = K2, t_end: float | None = None) -> StaringMetrics:
    """Eq. 6-8 for one run: t (n,) s, A_e (n,3) rad, omega_e (n,3) rad/s.

    t_end defaults to the last sample time (the windows must lie inside the recorded samples).
    """
    t = np.asarray(t, float)
    windows = plan.windows(t[-1] if t_end is None else t_end)
    idx = window_samples(t, windows)
    counts = {len(i) for i in idx}
    if len(counts) != 1 or 0 in counts:
        raise HostError("imaging windows do not hold equal numbers of samples; use a plant step "
                        "that divides T_img")
    sel = np.concatenate(idx)
    J_A = float(np.mean(np.abs(np.asarray(A_e, float)[sel] / DEG)))
    J_w = float(np.mean(np.abs(np.asarray(omega_e, float)[sel] / DEG)))
    return StaringMetrics(J_A=J_A, J_w=J_w, J=k1 * J_A + k2 * J_w, m=len(idx), p=counts.pop() - 1)


def average_metrics(runs: Sequence[StaringMetrics], k1: float = K1, k2: float = K2) -> StaringMetrics:
    """Eq. 25-27: plain means over targets (J̄ = k1·J̄_A + k2·J̄_ω by linearity)."""
    J_A = float(np.mean([r.J_A for r in runs]))
    J_w = float(np.mean([r.J_w for r in runs]))
    return StaringMetrics(J_A=J_A, J_w=J_w, J=k1 * J_A + k2 * J_w)
