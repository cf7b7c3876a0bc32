"""Compare float32 outputs bit for bit (as uint32 patterns), NaN included.

Every value must match exactly: the sign of zero, subnormals and NaN too. The generated units
make every output that can be NaN the canonical quiet NaN (sg_canonf / detmath.canonf), so no
NaN class is needed (x86 and ARM default NaNs differ in sign; the outputs never carry them).
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np


@dataclass(frozen=True)
class Mismatch:
    row: int
    column: int
    expected_bits: int
    actual_bits: int

    @property
    def expected(self) -> float:
        return float(np.uint32(self.expected_bits).view(np.float32))

    @property
    def actual(self) -> float:
        return float(np.uint32(self.actual_bits).view(np.float32))

    def describe(self, expected_name: str = "expected", actual_name: str = "actual") -> str:
        return (f"row {self.row} col {self.column}: {expected_name} 0x{self.expected_bits:08x} ({self.expected!r}) "
                f"!= {actual_name} 0x{self.actual_bits:08x} ({self.actual!r})")


@dataclass(frozen=True)
class Comparison:
    n_values: int
    n_mismatches: int
    mismatched_rows: np.ndarray
    first: list[Mismatch] = field(default_factory=list)

    @property
    def ok(self) -> bool:
        return self.n_mismatches == 0

    def report(self, expected_name: str = "expected", actual_name: str = "actual") -> list[str]:
        lines = [f"{self.n_mismatches} mismatches in {self.n_values} values "
                 f"({self.mismatched_rows.size} rows)"]
        lines += ["  " + m.describe(expected_name, actual_name) for m in self.first]
        return lines


def _bits(arr: np.ndarray, name: str) -> np.ndarray:
    arr = np.asarray(arr)
    if arr.dtype != np.float32:
        raise TypeError(f"bitcompare: {name} must be float32, got {arr.dtype}")
    return np.ascontiguousarray(arr).view(np.uint32)


def compare(expected: np.ndarray, actual: np.ndarray, limit: int = 5) -> Comparison:
    """Element-wise bit comparison of two float32 arrays of the same shape; keeps the first `limit` mismatches."""
    if np.shape(expected) != np.shape(actual):
        raise ValueError(f"bitcompare: shapes differ: {np.shape(expected)} vs {np.shape(actual)}")
    e_bits, a_bits = _bits(expected, "expected"), _bits(actual, "actual")
    bad = e_bits != a_bits
    bad2d = bad.reshape(bad.shape[0], -1) if bad.ndim else bad.reshape(1, 1)
    where = np.argwhere(bad2d)
    e2d, a2d = e_bits.reshape(bad2d.shape), a_bits.reshape(bad2d.shape)
    first = [Mismatch(int(r), int(c), int(e2d[r, c]), int(a2d[r, c])) for r, c in where[:limit]]
    rows = np.unique(where[:, 0]) if where.size else np.empty(0, dtype=np.int64)
    return Comparison(n_values=int(bad.size), n_mismatches=int(bad.sum()), mismatched_rows=rows, first=first)
