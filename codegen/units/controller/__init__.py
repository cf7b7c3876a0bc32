"""Unit `controller`: the whole flight controller of paper 001 Fig. 2 with its network inside."""
from codegen.unit import UnitKind
from codegen.units.controller.unit import configure

KIND = UnitKind(name="controller", summary="the whole Fig. 2 controller step (network inside, PID fallback)",
                needs=("artifact", "config"), configure=configure)
