"""Model artifact, deterministic float32 math, C emitter and the golden model that mirrors it."""

GENERATOR_VERSION = "0.1.0"
