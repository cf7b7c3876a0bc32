"""Unit `tanh`: paper 000's finite-time tanh saturation law with its auxiliary system."""
from codegen.unit import UnitKind
from codegen.units.tanh.params import example_params, load_params
from codegen.units.tanh.unit import configure

KIND = UnitKind(name="tanh", summary="paper 000's finite-time tanh saturation law (state: varpi)",
                needs=("params",), configure=configure, example=lambda: {"params": example_params()},
                load_params=load_params)
