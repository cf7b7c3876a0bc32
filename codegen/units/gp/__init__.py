"""Unit `gp` (paper 004, sparse-GP attitude takeover; docs/gp-takeover.md): for now only its artifact
(`codegen.units.gp.artifact`, format `staregen.gp-artifact` v1). The unit itself (UnitKind, golden model,
emitter) comes later; nothing is registered here."""

KIND = None     # under construction: the registry skips this folder (codegen/units/__init__.py)
