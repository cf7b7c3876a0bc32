"""Unit `rbf`: paper 002's RBF adaptive finite-time backstepping law (the weights adapt on board)."""
from codegen.unit import UnitKind
from codegen.units.rbf.params import example_params, load_params
from codegen.units.rbf.unit import configure

KIND = UnitKind(name="rbf",
                summary="paper 002's RBF adaptive finite-time backstepping law (state: the weights, the last command)",
                needs=("params",), configure=configure, example=lambda: {"params": example_params()},
                load_params=load_params)
