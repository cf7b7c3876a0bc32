"""Written once for every generated unit: runners (golden, x86, ARM), the bit-exact gate, the cycle / size /
stack report, the in-the-loop runner; the Cortex-M4 cycle model (m4/); setup and benchmark scripts."""
