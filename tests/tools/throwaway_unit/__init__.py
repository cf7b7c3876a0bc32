"""A throw-away unit that lives outside codegen: the saturated linear law u = clip(K x, -L, L).

It exists to show that a new unit is one folder and one registration (`KIND`, registered by the
test with codegen.units.register) and gets the gate, the cycle report and SIL/PIL for free.
"""
from codegen.unit import UnitKind
from tests.tools.throwaway_unit.unit import configure

KIND = UnitKind(name="satlin", summary="throw-away test unit: u = clip(K x)", needs=(), configure=configure,
                example=lambda: {})
