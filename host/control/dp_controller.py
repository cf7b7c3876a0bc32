"""The discrete-point law (seed paper 003) flown in the staring simulator as the network is: the
controller of Fig. 2 with the law in the network's place. Inside the Table 2 envelope (and with a
finite measurement) the law flies after `dwell_steps` clean steps; otherwise, or when the law
reports its input invalid, the Table 1 PID flies (the same mode logic, integrator and saturation
as host.control.nn_controller).

  dp     the float64 law (host.control.discrete_point) on the tables' float32 samples;
  dp-c   the generated C of the `dp` unit on x86 (SIL, through tools.inloop).
"""
from __future__ import annotations

import functools

import numpy as np

from codegen.artifact import table2_envelope
from codegen.unit import Batch
from codegen.units.dp import golden as dp_golden
from codegen.units.dp import tables as dp_tables
from codegen.units.dp.unit import DpUnit
from host.control.discrete_point import DpModel, DpTables as DpTables64
from host.control.nn_controller import Fig2Batch, Fig2Controller, flight_config
from host.errors import HostError
from tools.inloop import InTheLoop
from tools.runners import runner


@functools.lru_cache(maxsize=4)
def load_tables(path: str) -> dp_tables.DpTables:
    return dp_tables.load(path)


class Float64Law:
    """The float64 law on the tables' samples; returns (torque, invalid)."""

    def __init__(self, t: dp_tables.DpTables):
        X, Y = t.X.astype(np.float64), t.Y.astype(np.float64)
        self.model = DpModel(DpTables64.build(X, Y, t.params.n_min), t.params)

    def __call__(self, x_deg: np.ndarray) -> tuple[np.ndarray, bool]:
        if not np.all(np.isfinite(x_deg)):
            return np.zeros(3), True
        with np.errstate(all="ignore"):
            torque = self.model.query(x_deg).torque
        if not np.all(np.isfinite(torque)):
            return np.zeros(3), True        # the C's STATUS_INVALID
        return torque, False


class GeneratedLaw:
    """The generated step on x86 (cffi) through the one in-the-loop runner."""

    def __init__(self, t: dp_tables.DpTables, golden_twin: bool = False):
        self.loop = InTheLoop(DpUnit(t), "x86", golden_twin=golden_twin)

    def __call__(self, x_deg: np.ndarray) -> tuple[np.ndarray, bool]:
        rec = np.zeros(1, dtype=dp_golden.INPUT_DTYPE)
        with np.errstate(all="ignore"):
            rec["x"] = x_deg.astype(np.float32)
        out = self.loop.step(rec)
        return out["torque"][0].astype(float), bool(out["status"][0] & dp_golden.STATUS_INVALID)


class Float64LawRows:
    """Float64Law on rows (DpModel.query_rows: the same results as one query per row)."""

    def __init__(self, t: dp_tables.DpTables):
        self.model = Float64Law(t).model

    def __call__(self, x_deg: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        return self.model.query_rows(x_deg)


class GeneratedLawRows:
    """The generated step on x86 (cffi) for every flying row in one call of the unit's record runner."""

    def __init__(self, t: dp_tables.DpTables):
        self.unit = DpUnit(t)
        self.run = runner(self.unit, "x86")

    def __call__(self, x_deg: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        rec = np.zeros(len(x_deg), dtype=dp_golden.INPUT_DTYPE)
        with np.errstate(all="ignore"):
            rec["x"] = x_deg.astype(np.float32)
        out, _ = self.run.records(Batch(None, rec))
        return out["torque"].astype(float), (out["status"] & dp_golden.STATUS_INVALID) != 0


class DpBatch(Fig2Batch):
    """DpController on rows."""

    def __init__(self, name: str, law, torque_limit: float, control_period: float):
        super().__init__(name, table2_envelope(), flight_config(torque_limit, control_period))
        self._law = law

    def law(self, x_deg: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        return self._law(x_deg)


class DpController(Fig2Controller):
    law_mode = "dp"

    def __init__(self, name: str, law, torque_limit: float, control_period: float):
        super().__init__(table2_envelope(), flight_config(torque_limit, control_period))
        self.name, self._law = name, law

    def law(self, x_deg: np.ndarray) -> tuple[np.ndarray, bool]:
        return self._law(x_deg)


def _tables(tables: str | None) -> dp_tables.DpTables:
    if tables is None:
        raise HostError("the discrete-point controllers need tables= (a file written by `staregen dp build`)")
    return load_tables(str(tables))


def make_dp_controller(*, torque_limit: float, control_period: float, tables: str | None = None):
    return DpController("dp", Float64Law(_tables(tables)), torque_limit, control_period)


def make_dp_sil_controller(*, torque_limit: float, control_period: float, tables: str | None = None):
    return DpController("dp-c", GeneratedLaw(_tables(tables)), torque_limit, control_period)


def make_dp_batch(*, torque_limit: float, control_period: float, tables: str | None = None):
    return DpBatch("dp", Float64LawRows(_tables(tables)), torque_limit, control_period)


def make_dp_sil_batch(*, torque_limit: float, control_period: float, tables: str | None = None):
    return DpBatch("dp-c", GeneratedLawRows(_tables(tables)), torque_limit, control_period)
