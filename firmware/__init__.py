"""Hand-written C (startup, linker script, harness) and the ARM / x86 (cffi) builds."""
