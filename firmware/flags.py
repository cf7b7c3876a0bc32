"""The one place that states the compiler flags of SPEC section 5, for both targets."""

# Shared by x86-64 (SIL, cffi) and the Cortex-M4F (PIL). Nothing from the fast-math family and no
# tuning for the build machine (SPEC section 5): both targets must round exactly alike.
COMMON = [
    "-std=c99", "-pedantic", "-O2",
    "-ffp-contract=off", "-fno-math-errno", "-fexcess-precision=standard",
    "-Wall", "-Wextra", "-Wdouble-promotion", "-Wfloat-conversion", "-Werror",
]

# -fexcess-precision is GCC's alone: clang evaluates float in float on SSE and FPv4-SP anyway and
# rejects the flag under -Werror. The package's CMakeLists adds these for GCC only.
GCC_ONLY = ["-fexcess-precision=standard"]

# The rest of COMMON, understood alike by GCC, clang and armclang (the package's flight flags).
PORTABLE = [f for f in COMMON if f not in GCC_ONLY]

ARM_CPU = ["-mcpu=cortex-m4", "-mthumb", "-mfpu=fpv4-sp-d16", "-mfloat-abi=hard"]

ARM_CC = "arm-none-eabi-gcc"

# clang's name for the STM32F417's core (Thumb-2, hard-float ABI), given with ARM_CPU.
CLANG_ARM_TARGET = "thumbv7em-none-eabihf"


def with_opt(flags: list[str], opt: str) -> list[str]:
    """The same flags with the optimisation level replaced (benchmarks at -O0/-Os/-O2)."""
    return [opt if f.startswith("-O") else f for f in flags]
