"""Unit `gp`: paper 004's sparse-GP attitude takeover law (docs/gp-takeover.md): the GP's mean and
variance of the unknown torque, variance-scheduled gains, the wheel torque. Its parameter file names
the trained GP artifact (`staregen.gp-artifact`, codegen/units/gp/artifact.py)."""
from codegen.unit import UnitKind
from codegen.units.gp.example import example_params
from codegen.units.gp.params import load_params
from codegen.units.gp.unit import configure

KIND = UnitKind(name="gp",
                summary="paper 004's sparse-GP takeover law (GP mean and variance, scheduled gains; stateless)",
                needs=("params",), configure=configure, example=lambda: {"params": example_params()},
                load_params=load_params, takes_period=False)
