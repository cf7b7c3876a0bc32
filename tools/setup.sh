#!/usr/bin/env bash
# Idempotent set-up for a fresh Debian machine: the ARM toolchain, cmake and cppcheck from Debian, then the
# Python package (torch pinned to the CPU wheel first so nothing pulls CUDA builds).
# `setup.sh test` (make test) also installs the optional extra `basilisk` (bsk, Basilisk), which the tests
# of `staregen basilisk` run; the main job does not need it.
set -euo pipefail
cd "$(dirname "$0")/.."

SUDO=""
[ "$(id -u)" -ne 0 ] && SUDO="sudo"

if ! command -v arm-none-eabi-gcc >/dev/null 2>&1 \
   || ! [ -e /usr/lib/arm-none-eabi/newlib/thumb/v7e-m+fp/hard/libc.a ]; then
  echo "setup: installing gcc-arm-none-eabi and libnewlib-arm-none-eabi (apt)"
  $SUDO apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq gcc-arm-none-eabi libnewlib-arm-none-eabi >/dev/null
fi

# cmake builds the flight package with its own CMakeLists (staregen generate, package check, tests);
# cppcheck with its MISRA addon checks the generated C (staregen misra); llvm gives llvm-mca, the
# lower bound the cycle model's block costs are checked against (tools/m4/mca.py); clang builds the
# package as a firmware team on clang/armclang would; qemu-system-arm runs its image as a second emulator.
if ! command -v cmake >/dev/null 2>&1 || ! command -v cppcheck >/dev/null 2>&1 \
   || [ -z "$(compgen -c llvm-mca)" ] || ! command -v clang >/dev/null 2>&1 \
   || ! command -v qemu-system-arm >/dev/null 2>&1; then
  echo "setup: installing cmake, cppcheck, llvm, clang and qemu-system-arm (apt)"
  $SUDO apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq cmake cppcheck llvm clang qemu-system-arm >/dev/null
fi

extras="dev"
check="import host, codegen, tools, firmware, torch"
if [ "${1:-}" = "test" ]; then
  extras="dev,basilisk"
  check="$check, Basilisk"
fi
stamp=.setup-stamp
want="$(sha256sum pyproject.toml | cut -d' ' -f1) $extras"
if [ "$(cat "$stamp" 2>/dev/null)" != "$want" ] || ! python3 -c "$check" 2>/dev/null; then
  echo "setup: pip install torch==2.13.0 and -e .[$extras]"
  python3 -m pip install -q --disable-pip-version-check "torch==2.13.0"
  python3 -m pip install -q --disable-pip-version-check -e ".[$extras]"
  echo "$want" > "$stamp"
fi
