"""The batched controller interface: host.control.controllers' Controller with rows.

The batched simulator (host.sim.batched) flies R scenarios at once, laid out target-major as
(target, variant, seed) and flattened to rows r = (t·G + g)·N + n. Each control period it hands the
controller one BatchMeasurement (the inputs of paper 001 Fig. 2 for every row, SI units) and applies
the returned torques, held for one period. A "variant" is one of G versions of the controller
flown side by side on the same noise (e.g. PID gain sets in the Table 7 grid); most controllers
have one.

The float64 preprocessing (host.gnc.preprocess: desired state from the ideal GPS, A_bd, ω_e) is the
same for every host law, so the loop computes it once for all rows and the measurement carries it;
a law that computes its own (the generated C) reads the raw fields.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Protocol

import numpy as np

from host.core.constants import DEG
from host.errors import HostError


@dataclass(frozen=True)
class BatchLayout:
    """T targets × G variants × N seeds, flattened target-major to rows."""
    targets: int
    variants: int
    seeds: int

    def __post_init__(self):
        if min(self.targets, self.variants, self.seeds) < 1:
            raise HostError(f"a batch needs at least one target, variant and seed "
                            f"(got {self.targets}, {self.variants}, {self.seeds})")

    @property
    def rows(self) -> int:
        return self.targets * self.variants * self.seeds

    def per_variant(self, a) -> np.ndarray:
        """(G, ...) values -> (rows, ...): each row gets its variant's value."""
        a = np.asarray(a)
        if a.shape[0] != self.variants:
            raise HostError(f"{a.shape[0]} variant values for {self.variants} variants")
        per = np.repeat(a, self.seeds, axis=0)
        return np.tile(per, (self.targets,) + (1,) * (a.ndim - 1))

    def per_target(self, a) -> np.ndarray:
        """(T, ...) values -> (rows, ...): each row gets its target's value."""
        a = np.asarray(a)
        if a.shape[0] != self.targets:
            raise HostError(f"{a.shape[0]} target values for {self.targets} targets")
        return np.repeat(a, self.variants * self.seeds, axis=0)


@dataclass(frozen=True)
class BatchMeasurement:
    """One control instant for every row. Raw fields as in host.control.controllers.Measurement
    (rows of A_bo and ω_b; one orbit and one clock for all rows), plus the float64 preprocessing."""
    t: float
    jd_days: int
    sec_of_day: float
    R_s: np.ndarray          # (3,) ECI position, m (ideal GPS)
    V_s: np.ndarray          # (3,) ECI velocity, m/s
    lon: np.ndarray          # (R,) target longitude, rad
    lat: np.ndarray          # (R,) target latitude, rad
    A_bo: np.ndarray         # (R, 3) measured 3-1-2 angles of body w.r.t. orbital frame, rad
    omega_b: np.ndarray      # (R, 3) measured body rate, rad/s
    A_bd: np.ndarray         # (R, 3) from the measurement: euler312(L_bo·L_oi·L_di^T), rad
    omega_e: np.ndarray      # (R, 3) ω_b − ω_d, rad/s
    omega_d: np.ndarray      # (R, 3) desired rate, rad/s
    omegadot_d: np.ndarray   # (R, 3) its derivative, rad/s²

    @property
    def rows(self) -> int:
        return self.A_bo.shape[0]

    def select(self, rows: np.ndarray) -> "BatchMeasurement":
        """The same instant for a subset of the rows (in the given order)."""
        per_row = {f: getattr(self, f)[rows] for f in ("lon", "lat", "A_bo", "omega_b", "A_bd", "omega_e",
                                                         "omega_d", "omegadot_d")}
        return BatchMeasurement(t=self.t, jd_days=self.jd_days, sec_of_day=self.sec_of_day, R_s=self.R_s,
                                V_s=self.V_s, **per_row)

    def network_inputs_deg(self) -> np.ndarray:
        """(R, 12) S_in of eq. 11 in Table 2 units, as ControllerInputs.network_inputs_deg per row."""
        return np.concatenate([self.omega_d, self.omegadot_d, self.A_bd, self.omega_e], axis=1) / DEG

    def finite(self) -> np.ndarray:
        """(R,) every raw input finite (host.control.nn_controller.measurement_finite per row)."""
        shared = bool(np.all(np.isfinite(self.R_s)) and np.all(np.isfinite(self.V_s))
                      and np.isfinite(self.sec_of_day))
        rows = (np.all(np.isfinite(self.A_bo), 1) & np.all(np.isfinite(self.omega_b), 1)
                & np.isfinite(self.lon) & np.isfinite(self.lat))
        return rows & shared


@dataclass(frozen=True)
class BatchOutput:
    torque: np.ndarray       # (R, 3) commanded wheel torque, N·m, body axes
    saturated: np.ndarray    # (R,) the command was clipped on some axis this step


class BatchController(Protocol):
    name: str
    variants: int

    def reset(self, layout: BatchLayout) -> None: ...

    def step(self, m: BatchMeasurement) -> BatchOutput: ...


class ControllerBank:
    """Several batch controllers flown side by side as the variants of one batch: the same targets,
    seeds and noise for all, member i owning the next `variants` of them. One batched run of the
    bank costs little more than one of a single controller (numpy's per-call cost dominates at a
    hundred rows), so an evaluation flies every controller in one run."""

    def __init__(self, members):
        self.members = list(members)
        if not self.members:
            raise HostError("a controller bank needs at least one controller")
        self.name = "+".join(c.name for c in self.members)
        self.variants = sum(int(c.variants) for c in self.members)

    def spans(self) -> list[tuple[int, int]]:
        """[first, end) variant index of each member."""
        ends = np.cumsum([int(c.variants) for c in self.members])
        return [(int(e - c.variants), int(e)) for c, e in zip(self.members, ends)]

    def reset(self, layout: BatchLayout) -> None:
        index = np.arange(layout.rows).reshape(layout.targets, layout.variants, layout.seeds)
        self.rows = []
        for c, (lo, hi) in zip(self.members, self.spans()):
            self.rows.append(index[:, lo:hi, :].ravel())
            c.reset(BatchLayout(layout.targets, hi - lo, layout.seeds))
        self.total = layout.rows

    def step(self, m: BatchMeasurement) -> BatchOutput:
        torque, saturated = np.empty((self.total, 3)), np.empty(self.total, bool)
        for c, rows in zip(self.members, self.rows):
            out = c.step(m.select(rows))
            torque[rows], saturated[rows] = out.torque, out.saturated
        return BatchOutput(torque=torque, saturated=saturated)
