"""The network path (normalise -> 12-40-3 tansig MLP -> denormalise) as a generated unit.

Stateless: input record `x` (n_in float32, Table 2 units), output record `y` (n_out float32,
N·m); the C entry is `<name>_eval(const float x[], float y[])`, and normalise / mlp /
denormalise are exposed as stages for the stage-by-stage tests. mapminmax is folded into the
layers at generation (fold.py), so the stages are what is left at run time: normalise the
subtraction of the centred inputs' offsets, mlp the folded MLP (raw output units), denormalise
the canonical-NaN rule.
"""
from __future__ import annotations

import numpy as np

from codegen.artifact import Artifact
from codegen.errors import CodegenError
from codegen.units.network import interface
from codegen.unit import Batch, Budgets, Stage, Unit
from codegen.units.network import golden, reference, vectors
from codegen.units.network.emit import DEFAULT_NAME, network_sources

# SPEC section 8 budgets of the network path (ideal memory).
BUDGETS = Budgets(cycles=3_000, cycles_art=3_300, flash=16 * 1024, ram=None, stack=512)


def row_dtype(field: str, n: int) -> np.dtype:
    return np.dtype([(field, "<f4", (n,))])


class NetworkUnit(Unit):
    kind = "network"

    def __init__(self, artifact: Artifact, name: str = DEFAULT_NAME):
        self.artifact = artifact
        self._sources = network_sources(artifact, name)
        super().__init__(name, row_dtype("x", artifact.n_in), row_dtype("y", artifact.n_out), None, BUDGETS)

    def identity(self) -> str:
        return f"network ({self.entry}_eval), {self.artifact.shape_text}, sha256 {self.artifact.sha256[:16]}"

    def sources(self) -> dict[str, str]:
        return dict(self._sources)

    def field_docs(self):
        return interface.field_docs(self.artifact)

    def status_bits(self):
        return interface.status_bits()

    @property
    def step_symbol(self) -> str:
        return f"{self.entry}_eval"

    @property
    def c_types(self) -> dict[str, str]:
        P = self.entry.upper()
        return {"input": f"float[{P}_N_IN]", "output": f"float[{P}_N_OUT]"}

    @property
    def stages(self) -> dict[str, Stage]:
        a, P = self.artifact, self.entry.upper()
        n_in, n_out = a.n_in, a.n_out

        def stage(name, fn, rows_in, rows_out, c_in, c_out):
            dt_in, dt_out = row_dtype("x", rows_in), row_dtype("y", rows_out)

            def run(x):
                out = np.zeros(x.shape[0], dtype=dt_out)
                out["y"] = fn(a, np.ascontiguousarray(x["x"]))
                return out
            return Stage(f"{self.entry}_{name}", dt_in, dt_out, run, f"float[{P}_{c_in}]", f"float[{P}_{c_out}]")
        return {"normalise": stage("normalise", golden.normalise, n_in, n_in, "N_IN", "N_IN"),
                "mlp": stage("mlp", golden.mlp, n_in, n_out, "N_IN", "N_OUT"),
                "denormalise": stage("denormalise", golden.denormalise, n_out, n_out, "N_OUT", "N_OUT")}

    def golden(self, state, inp):
        out = np.zeros(inp.shape[0], dtype=self.output_dtype)
        out["y"] = golden.network_eval(self.artifact, np.ascontiguousarray(inp["x"]))
        return out, None

    def _batch(self, x: np.ndarray) -> Batch:
        rec = np.zeros(x.shape[0], dtype=self.input_dtype)
        rec["x"] = x
        return Batch(None, rec)

    def gate_classes(self, n: int, seed: int) -> dict[str, Batch]:
        vs = vectors.gate_vectors(self.artifact.envelope, n, seed)
        return {name: self._batch(vs.x[vs.kind == k]) for k, name in enumerate(vectors.KINDS)}

    def cycle_classes(self, per_class: int, seed: int) -> dict[str, Batch]:
        return {c: self._batch(x) for c, x in vectors.class_vectors(self.artifact.envelope, per_class, seed).items()}

    def extra_report(self, batches, outputs) -> list[str]:
        """Golden vs the float64 reference on the in-envelope rows (absolute and per output range)."""
        a = self.artifact
        x = np.concatenate([b.input["x"] for b in batches.values()])
        y = np.concatenate([o["y"] for o in outputs.values()])
        inside = vectors.inside_mask(a.envelope, x)
        if not inside.any():
            return ["golden vs float64 reference: no in-envelope vectors"]
        err = np.abs(y[inside].astype(np.float64) - reference.reference_eval64(a, x[inside])).max(axis=0)
        span = a.output_map.xmax - a.output_map.xmin
        rel = err / np.where(span > 0, span, 1.0)
        per_out = ", ".join(f"{n} {e:.3g} {u}" for n, e, u in zip(a.outputs.names, err, a.outputs.units))
        return [f"golden vs float64 reference ({int(inside.sum())} in-envelope vectors): max |error| {per_out}",
                f"  max |error| / output range: {rel.max():.3g}"]


def configure(artifact: Artifact | None = None, name: str | None = None, **_ignored) -> NetworkUnit:
    if artifact is None:
        raise CodegenError("unit network needs --artifact FILE")
    return NetworkUnit(artifact, name or DEFAULT_NAME)
