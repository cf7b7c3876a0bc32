"""Unit `network`: the normalise -> MLP -> denormalise path of a model artifact (mapminmax folded into the layers)."""
from codegen.artifact import random_artifact
from codegen.unit import UnitKind
from codegen.units.network.unit import configure

KIND = UnitKind(name="network", summary="the network path of a model artifact (normalise, MLP, denormalise)",
                needs=("artifact",), configure=configure,
                example=lambda: {"artifact": random_artifact((12, 40, 3), seed=1)})
