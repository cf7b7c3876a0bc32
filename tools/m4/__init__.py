"""Cortex-M4 on Unicorn: ELF image, machine, Capstone decoding, timing table, memory models,
cycle profiler and the host side of the firmware harness. See docs/cycle-model.md."""
