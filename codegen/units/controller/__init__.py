"""Unit `controller`: the whole flight controller of paper 001 Fig. 2 with its network inside."""
from codegen.artifact import random_artifact
from codegen.unit import UnitKind
from codegen.units.controller.unit import configure

# The example's configuration (gains, limits, Earth constants) and realistic inputs come from the
# host (host.sim.scenarios.unit_inputs), like every binding of this unit.
KIND = UnitKind(name="controller", summary="the whole Fig. 2 controller step (network inside, PID fallback)",
                needs=("artifact", "config"), configure=configure,
                example=lambda: {"artifact": random_artifact((12, 40, 3), seed=1)})
