"""Unit `dp`: the discrete-point controller of seed paper 003 (anchor samples, box search, IRLS)."""
from codegen.unit import UnitKind
from codegen.units.dp.tables import random_tables
from codegen.units.dp.unit import configure

KIND = UnitKind(name="dp", summary="the discrete-point controller of paper 003 (samples, box search, IRLS)",
                needs=("tables",), configure=configure, example=lambda: {"tables": random_tables()})
