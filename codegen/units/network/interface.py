"""The network unit's interface for the ICD: its two arrays, element by element from the artifact."""
from __future__ import annotations

from codegen.artifact import Artifact
from codegen.unit import FieldDoc


def field_docs(a: Artifact) -> dict[str, list[FieldDoc]]:
    env = a.envelope
    inputs = "; ".join(f"x[{i}] {n} ({u})" for i, (n, u) in enumerate(zip(env.names, env.units)))
    outputs = "; ".join(f"y[{i}] {n} ({u})" for i, (n, u) in enumerate(zip(a.outputs.names, a.outputs.units)))
    return {
        "input": [FieldDoc("x", "per element (below)", "-", "the envelope of the artifact; any float is evaluated",
                           inputs)],
        "output": [FieldDoc("y", "per element (below)", "-", "finite for finite inputs", outputs)],
    }
