"""The flight package: what `staregen generate` hands a firmware team.

    DIR/
      include/   <name>.h, <name>_nn.h, sg_math.h [, <name>_tanh.h]     the units' headers
      src/       <name>.c, <name>_nn.c, sg_math.c [, <name>_tanh.c]     the units' sources
      selftest/  <name>_selftest.h, <name>_selftest.c                  golden vectors as hex words
      CMakeLists.txt   add_subdirectory()-able: targets <name> and <name>_selftest, the flight flags
      ICD.md           interface control document
      manifest.json    sha256 of every file and input, flags, compiler, measured evidence

The controller unit's entry is <name> (<name>_init, <name>_step); every other unit the
configuration includes (the tanh law, the RBF law) is <name>_<unit>. `int <name>_selftest(void)` returns the number of
mismatching 32-bit words over every embedded vector of every unit plus failed floating-point
environment checks (0 = pass); `<name>_selftest_reference(&state, &input)` gives the controller's
timing reference step (vector 0), whose cycles the manifest records.

This package (codegen) renders the files from bound units, their golden vectors and measured
evidence passed in as data; tools/package.py measures the evidence and writes the folder.
"""
