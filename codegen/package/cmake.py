"""The flight package's CMakeLists.txt: two static libraries, `<name>` (the flight C) and
`<name>_selftest`, carrying the flight flags; usable with add_subdirectory() or on its own.
Every name and file name is checked before it reaches CMake (nothing unescaped from a file)."""
from __future__ import annotations

import re
from pathlib import Path

from codegen.cgen import check_name, environment
from codegen.errors import CodegenError

TEMPLATES = Path(__file__).with_name("templates")
FILE_NAME = re.compile(r"[A-Za-z0-9_]+\.[ch]")
FLAG = re.compile(r"-[A-Za-z0-9_=+.-]+")


def cmake_lists(name: str, headers: list[str], sources: list[str], selftest_sources: list[str], flags: list[str],
                generator_version: str, gcc_flags: list[str] = ()) -> str:
    """flags: for every compiler (GCC, Clang, armclang); gcc_flags: added when the compiler is GCC."""
    check_name(name)
    for f in [*headers, *sources, *selftest_sources]:
        if not FILE_NAME.fullmatch(f):
            raise CodegenError(f"package: file name {f!r} is not [A-Za-z0-9_]+.c/.h")
    for f in [*flags, *gcc_flags]:
        if not FLAG.fullmatch(f):
            raise CodegenError(f"package: compiler flag {f!r} is not a plain option")
    ctx = {"name": name, "generator_version": generator_version, "flags": list(flags), "gcc_flags": list(gcc_flags),
           "sources": sorted(s for s in sources if s.endswith(".c")),
           "selftest_sources": sorted(s for s in selftest_sources if s.endswith(".c"))}
    return environment(TEMPLATES).get_template("CMakeLists.txt.j2").render(ctx)
