"""Unit `network`: the normalise -> MLP -> denormalise path of a model artifact."""
from codegen.unit import UnitKind
from codegen.units.network.unit import configure

KIND = UnitKind(name="network", summary="the network path of a model artifact (normalise, MLP, denormalise)",
                needs=("artifact",), configure=configure)
