"""Model artifact, deterministic float32 math, the generated-unit interface (unit.py) and one folder per
unit in units/ (emitter, templates, golden model, gate vectors)."""

GENERATOR_VERSION = "0.1.0"
