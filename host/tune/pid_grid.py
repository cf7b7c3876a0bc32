"""The PID gain grids of paper 001 Table 7, and how "each axis optimised respectively" is read.

Table 7 searches Kp in 1..60, Ki in 0..0.03 and Kd in 40..90 and says each axis is optimised
respectively. We read it as one grid of (Kp, Ki, Kd) triples, flown with the same triple on all
three axes, and an argmin per axis of that axis's share of eq. 8 (k1·mean|A_e,i| + k2·mean|ω_e,i|,
averaged over the targets). Why: the axes are close to decoupled (products of inertia are 2-8 %
of the moments, gyroscopic coupling is second order in ω ≈ 1e-3 rad/s), so one run per triple
gives every axis's response to it and the 60·4·51 = 12,240 triples need 12,240 runs per target
instead of 12,240³. The coupling that remains is measured, not assumed away: the tuned gains
(a different triple per axis) are flown again beside Table 1 and both J̄ are reported.

The steps: Kp and Kd in steps of 1 (Table 1's integer gains lie on the grid), Ki in steps of 0.01.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from codegen.number_text import parse_real
from host.errors import HostError


@dataclass(frozen=True)
class PidGrid:
    name: str
    kp: tuple[float, ...]
    ki: tuple[float, ...]
    kd: tuple[float, ...]

    def __post_init__(self):
        for key in ("kp", "ki", "kd"):
            values = getattr(self, key)
            if len(values) == 0:
                raise HostError(f"grid {self.name}: {key} has no values")
            if not all(np.isfinite(v) and v >= 0.0 for v in values):
                raise HostError(f"grid {self.name}: {key} values must be finite and >= 0")

    def __len__(self) -> int:
        return len(self.kp) * len(self.ki) * len(self.kd)

    def triples(self, start: int = 0, stop: int | None = None) -> np.ndarray:
        """(G, 3) rows (kp, ki, kd) in index order: kp slowest, kd fastest."""
        stop = len(self) if stop is None else stop
        idx = np.arange(start, stop)
        n_ki, n_kd = len(self.ki), len(self.kd)
        return np.stack([np.asarray(self.kp)[idx // (n_ki * n_kd)], np.asarray(self.ki)[(idx // n_kd) % n_ki],
                         np.asarray(self.kd)[idx % n_kd]], -1).astype(float)

    def index_of(self, kp: float, ki: float, kd: float) -> int | None:
        """Grid index of a triple, or None when it is not on the grid."""
        try:
            a, b, c = self.kp.index(kp), self.ki.index(ki), self.kd.index(kd)
        except ValueError:
            return None
        return (a * len(self.ki) + b) * len(self.kd) + c

    def as_dict(self) -> dict:
        return {"name": self.name, "kp": list(self.kp), "ki": list(self.ki), "kd": list(self.kd)}


def _steps(lo: float, hi: float, step: float) -> tuple[float, ...]:
    n = int(round((hi - lo) / step))
    return tuple(round(lo + i * step, 10) for i in range(n + 1))


GRIDS = {
    # the paper's Table 7 ranges: 60 x 4 x 51 = 12,240 triples
    "table7": PidGrid("table7", _steps(1.0, 60.0, 1.0), _steps(0.0, 0.03, 0.01), _steps(40.0, 90.0, 1.0)),
    # CI and the pipeline: 6 x 2 x 5 = 60 triples spanning the same box, Table 1's gains included
    "coarse": PidGrid("coarse", (5.0, 17.0, 18.0, 30.0, 54.0, 60.0), (0.0, 0.03), (40.0, 46.0, 50.0, 77.0, 90.0)),
}


MAX_TRIPLES = 1_000_000


def _axis_values(key: str, spec: str) -> tuple[float, ...]:
    """`V` or `LO:HI:STEP` (both ends included when HI lies on the step)."""
    parts = spec.split(":")
    try:
        nums = [parse_real(p) for p in parts]   # ASCII digits: no `1_0`
    except ValueError:
        raise HostError(f"grid {key}={spec}: expected a number or LO:HI:STEP") from None
    if len(nums) not in (1, 3) or not all(np.isfinite(nums)):
        raise HostError(f"grid {key}={spec}: expected a number or LO:HI:STEP")
    if len(nums) == 1:
        return (nums[0],)
    lo, hi, step = nums
    if step <= 0:
        raise HostError(f"grid {key}={spec}: the step must be > 0")
    if hi < lo:
        raise HostError(f"grid {key}={spec}: empty range (HI < LO)")
    if (hi - lo) / step > MAX_TRIPLES:
        raise HostError(f"grid {key}={spec}: more than {MAX_TRIPLES} values")
    return _steps(lo, lo + step * np.floor((hi - lo) / step + 1e-9), step)


def grid(text: str) -> PidGrid:
    """A preset name (table7, coarse) or `kp=SPEC,ki=SPEC,kd=SPEC` with SPEC a number or LO:HI:STEP."""
    if text in GRIDS:
        return GRIDS[text]
    if "=" not in text:
        raise HostError(f"unknown grid {text!r} (known: {', '.join(sorted(GRIDS))}, or kp=LO:HI:STEP,ki=...,kd=...)")
    specs = {}
    for item in text.split(","):
        key, _, spec = item.partition("=")
        key = key.strip()
        if key not in ("kp", "ki", "kd"):
            raise HostError(f"grid: unknown key {key!r} (kp, ki, kd)")
        if key in specs:
            raise HostError(f"grid: {key} given twice")
        specs[key] = _axis_values(key, spec.strip())
    missing = [k for k in ("kp", "ki", "kd") if k not in specs]
    if missing:
        raise HostError(f"grid: missing {', '.join(missing)}")
    g = PidGrid("custom", specs["kp"], specs["ki"], specs["kd"])
    if len(g) > MAX_TRIPLES:
        raise HostError(f"grid: {len(g)} triples, more than {MAX_TRIPLES}")
    return g
