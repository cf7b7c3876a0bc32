"""The discrete-point unit's interface for the flight package's ICD: fields and status bits."""
from __future__ import annotations

from codegen.artifact import TABLE2_NAMES, TABLE2_UNITS
from codegen.unit import FieldDoc, StatusBit
from codegen.units.dp.golden import STATUS_EVERY_SAMPLE, STATUS_INVALID, STATUS_SINGULAR, STATUS_WIDENED
from codegen.units.dp.tables import DpTables


def field_docs(t: DpTables) -> dict[str, list[FieldDoc]]:
    names = ", ".join(f"x[{i}] {n} [{u}]" for i, (n, u) in enumerate(zip(TABLE2_NAMES, TABLE2_UNITS)))
    return {
        "input": [FieldDoc("x", "Table 2 units", "S_b / 3-1-2", "any float; non-finite -> zero torque, "
                           "STATUS_INVALID; outside the samples' range -> wider boxes, at last every sample",
                           f"the 12 network inputs of paper 001 Table 2: {names}")],
        "output": [
            FieldDoc("torque", "N*m", "S_b", "finite; 0 with STATUS_INVALID; not saturated (the caller clips)",
                     "the local robust fit's torque at the input"),
            FieldDoc("found", "-", "-", f"[0, {t.n}]", "samples in the box used, before the S_limit cap"),
            FieldDoc("used", "-", "-", f"[0, {t.params.s_limit}]", "samples in the fit"),
            FieldDoc("level", "-", "-", f"[0, {t.n_levels}]; {t.n_levels} = every sample",
                     f"box level used (side {t.params.r:g} x {t.params.widen:g}^level of each range)"),
            FieldDoc("status", "bits", "-", "STATUS_* bits below", "what the step did"),
        ],
    }


def status_bits() -> list[StatusBit]:
    return [
        StatusBit("STATUS_WIDENED", STATUS_WIDENED, "a box wider than level 0 was needed (information)"),
        StatusBit("STATUS_EVERY_SAMPLE", STATUS_EVERY_SAMPLE,
                  "no box held n_min samples (input far from every sample): a global fit; caller: consider "
                  "the fallback controller"),
        StatusBit("STATUS_SINGULAR", STATUS_SINGULAR, "a fit's system was not positive definite: the weighted "
                  "mean of the neighbourhood's torques (telemetry)"),
        StatusBit("STATUS_INVALID", STATUS_INVALID, "non-finite input or result: zero torque; caller: fly the "
                  "fallback controller (PID)"),
    ]
