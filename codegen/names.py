"""The one rule for a package's name (`package.name` of controller.toml, `--name`), checked where
the name is read so that nothing derived from it fails later.

The name prefixes C identifiers (`<name>_step`, `<name>_nn_eval`, `<name>_selftest_reference`),
upper-cased macros, file names (`<name>.h`, `<name>_selftest.h`) and CMake targets (`<name>`,
`<name>_selftest`) that sit beside the test image's own (`image`, sg_*). So it must be a short
lower-case C identifier, no C keyword, no standard header's name (the package's folder is on
the include path: `stdint.h` there would hide the compiler's), no CMake-reserved or image
target, and not the math library's `sg` prefix.
"""
from __future__ import annotations

import re

NAME = re.compile(r"[a-z][a-z0-9_]{0,11}")          # <name>_selftest_reference stays within C99's 31 characters
IDENTIFIER = re.compile(r"[a-z][a-z0-9_]{0,30}")    # any generated entry (derived names included)
MAX_NAME = 12

# Names derived from the package name (entries of each unit, the self-test and its targets).
DERIVED_SUFFIXES = ("_nn", "_tanh", "_dp", "_selftest", "_selftest_reference")

C_KEYWORDS = frozenset("""
    auto break case char const continue default do double else enum extern float for goto if inline int
    long register restrict return short signed sizeof static struct switch typedef union unsigned void
    volatile while alignas alignof bool constexpr false nullptr static_assert thread_local true typeof
    typeof_unqual asm fortran
""".split())
C_HEADERS = frozenset("""
    assert complex ctype errno fenv float inttypes iso646 limits locale math setjmp signal stdalign stdarg
    stdatomic stdbit stdbool stdckdint stddef stdint stdio stdlib stdnoreturn string tgmath threads time
    uchar wchar wctype harness startup main
""".split())   # harness, startup, main: the test image's own files (firmware/)
CMAKE_TARGETS = frozenset("""
    all clean help install preinstall test package package_source edit_cache rebuild_cache depend
    list_install_components image
""".split())   # CMake's reserved targets (CMP0037) and the test image's executable


def identifier_problem(ident) -> str | None:
    """None, or why `ident` cannot be a generated C entry name (derived names included)."""
    if not isinstance(ident, str) or not IDENTIFIER.fullmatch(ident):
        return "must be a lower-case C identifier (a-z, 0-9, _; at most 31 characters)"
    if ident == "sg" or ident.startswith("sg_"):
        return "must not be 'sg' or start with 'sg_' (the math library's prefix)"
    if ident in C_KEYWORDS:
        return "must not be a C keyword"
    return None


def name_problem(name) -> str | None:
    """None, or why `name` cannot name a package (every name derived from it is then valid)."""
    if not isinstance(name, str) or not NAME.fullmatch(name):
        return (f"must be a lower-case C identifier of at most {MAX_NAME} characters (a-z, 0-9, _), "
                "starting with a letter")
    if name in C_HEADERS:
        return "must not be the name of a C standard header or of the test image's files"
    if name in CMAKE_TARGETS or f"{name}_selftest" in CMAKE_TARGETS:
        return "must not be a CMake-reserved target or the test image's target"
    for ident in (name, *(name + s for s in DERIVED_SUFFIXES)):
        problem = identifier_problem(ident)
        if problem:
            return problem if ident == name else f"must give valid entries, but {ident!r} {problem}"
    return None


def show(name) -> str:
    text = repr(name)
    return text if len(text) <= 40 else text[:37] + "..."
