"""The discrete-point controller's settings (seed paper 003; docs/discrete-point.md) and their one
validator. Lives in codegen because the C generator bakes them in and codegen must not import host;
host.control.discrete_point uses the same class. Errors are one-line `DpParamsError`s."""
from __future__ import annotations

import math
from dataclasses import asdict, dataclass

from codegen import values
from codegen.errors import CodegenError

N_IN, N_OUT = 12, 3
N_PARAM = N_IN + 1            # affine fit: intercept + 12 slopes
MAX_ITERATIONS = 20
LAST_SIDE = 2.0               # a box of side 2·range centred inside the range holds every sample
MAX_LEVELS = 64               # boxed levels at most (r and widen are refused beyond it)
MAX_TUKEY_C = 1000.0
# (key, low, high, low open, high open) of the reals, checked once more after rounding to float32
FLOAT32_RANGES = (("r", 0.0, 1.0, True, True), ("widen", 1.0, 4.0, True, False),
                  ("tukey_c", 0.0, MAX_TUKEY_C, True, False), ("ridge", 0.0, 1.0, False, False))


class DpParamsError(CodegenError):
    """A bad discrete-point setting."""


@dataclass(frozen=True)
class DpParams:
    """Every number that shapes the controller's output besides the samples."""
    r: float = 0.5               # level-0 box side, a fraction of each range (paper 003: 0.05-0.09; same result here, fewer scans)
    s_limit: int = 64            # at most this many points enter the fit (paper 003: 256 / 512)
    n_min: int = 26              # fewer points in a level's box: widen (2 x 13 parameters)
    iterations: int = 1          # IRLS reweightings after the unweighted fit (more change nothing here: BENCHMARKS)
    tukey_c: float = 4.685       # bisquare tuning constant (95 % Gaussian efficiency)
    ridge: float = 1e-6          # added to the slope diagonal, relative to the weight sum
    widen: float = 1.25          # box side factor from one level to the next (2: 0.85 % -> 1.59 % error)

    def validate(self) -> "DpParams":
        def number(x) -> bool:
            if not isinstance(x, float | int) or isinstance(x, bool):
                return False
            try:
                return math.isfinite(float(x))
            except OverflowError:       # a JSON integer of hundreds of digits
                return False

        def integer(x) -> bool:
            return isinstance(x, int) and not isinstance(x, bool)
        if not (number(self.r) and 0.0 < self.r < 1.0):
            raise DpParamsError(f"discrete-point r must lie in (0, 1) (a fraction of each range), got {self.r}")
        if not (integer(self.s_limit) and N_PARAM <= self.s_limit <= 4096):
            raise DpParamsError(f"discrete-point S_limit must be an integer in [{N_PARAM}, 4096] (at least the "
                                f"affine fit's {N_PARAM} parameters), got {self.s_limit}")
        if not (integer(self.n_min) and N_PARAM <= self.n_min <= self.s_limit):
            raise DpParamsError(f"discrete-point n_min must be an integer in [{N_PARAM}, S_limit = {self.s_limit}], "
                                f"got {self.n_min}")
        if not (integer(self.iterations) and 0 <= self.iterations <= MAX_ITERATIONS):
            raise DpParamsError(f"discrete-point IRLS iterations must be an integer in [0, {MAX_ITERATIONS}], "
                                f"got {self.iterations}")
        if not (number(self.widen) and 1.0 < self.widen <= 4.0):
            raise DpParamsError(f"discrete-point widening factor must lie in (1, 4], got {self.widen}")
        levels = math.ceil((math.log(LAST_SIDE) - math.log(self.r)) / math.log(self.widen))
        if levels > MAX_LEVELS:
            raise DpParamsError(f"discrete-point r = {self.r:g} and widen = {self.widen:g} give {levels} box levels; "
                                f"at most {MAX_LEVELS} (raise r or widen)")
        if not (number(self.tukey_c) and 0 < self.tukey_c <= MAX_TUKEY_C and number(self.ridge)
                and 0 <= self.ridge <= 1):
            raise DpParamsError(f"discrete-point tukey_c must lie in (0, {MAX_TUKEY_C:g}] and ridge in [0, 1]")
        for key, low, high, low_open, high_open in FLOAT32_RANGES:   # again on the float32 the C holds
            values.float32_in(getattr(self, key), f"discrete-point {key}", low, high, low_open=low_open,
                              high_open=high_open, error=DpParamsError)
        return self

    def sides(self) -> tuple[float, ...]:
        """Box sides (fractions of the range) of the boxed levels: r·widen^l while below 2; after
        them a last level takes every sample."""
        out, side = [], float(self.r)
        while side < LAST_SIDE and len(out) < MAX_LEVELS:
            out.append(side)
            side *= float(self.widen)
        return tuple(out)

    def to_dict(self) -> dict:
        return asdict(self)
