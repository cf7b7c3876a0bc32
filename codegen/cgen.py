"""What every generated unit's emitter shares: exact C literals, entry names, the jinja2
environment (a unit's own templates plus the shared ones in codegen/templates), the
deterministic math library copied beside the unit, and atomic writing of the sources.

Generation is a pure function of its inputs and the generator version: no timestamps, no paths,
no dict-order dependence, so the same inputs give byte-identical sources.
"""
from __future__ import annotations

import os
from pathlib import Path

import jinja2
import numpy as np

from codegen import atomic
from codegen.artifact import comment_text_problem, hex_float
from codegen.errors import CodegenError
from codegen.names import identifier_problem, show

SHARED_TEMPLATES = Path(__file__).with_name("templates")
CSRC = Path(__file__).with_name("csrc")
MATH_FILES = ("sg_math.h", "sg_math.c")


def c_float(value) -> str:
    """A float32 as a C hex-float literal that round-trips exactly, e.g. 0x1.99999ap-4f."""
    v = np.float32(value)
    if not np.isfinite(v):
        raise CodegenError(f"cannot emit the non-finite constant {v} as a C literal")
    return hex_float(float(v)) + "f"


def comment(text) -> str:
    """Text that goes into a C comment, checked again at emission (the artifact loader checks it
    first): printable ASCII without '*/', '/*', '??' or a trailing backslash."""
    problem = comment_text_problem(text)
    if problem:
        raise CodegenError(f"comment text {str(text)[:40]!r}: {problem}")
    return text


def check_name(name: str) -> str:
    """Entry names become C identifiers and file names (codegen.names.identifier_problem; a
    package's name is checked against the stricter codegen.names.name_problem where it is read)."""
    problem = identifier_problem(name)
    if problem:
        raise CodegenError(f"entry name {show(name)}: {problem}")
    return name


def environment(unit_templates: Path) -> jinja2.Environment:
    """Templates are looked up in the unit's own folder first, then in the shared one."""
    return jinja2.Environment(
        loader=jinja2.FileSystemLoader([str(unit_templates), str(SHARED_TEMPLATES)]),
        undefined=jinja2.StrictUndefined, trim_blocks=True, lstrip_blocks=True,
        keep_trailing_newline=True, autoescape=False,
    )


def unit_sources(templates: Path, stem: str, name: str, ctx: dict, with_math: bool = True) -> dict[str, str]:
    """`<name>.h` and `<name>.c` rendered from the unit's `<stem>.h.j2` / `<stem>.c.j2`, and (by
    default) the math library beside them."""
    env = environment(templates)
    sources = {f"{name}.h": env.get_template(f"{stem}.h.j2").render(ctx),
               f"{name}.c": env.get_template(f"{stem}.c.j2").render(ctx)}
    if with_math:
        sources.update(math_sources())
    return sources


def math_sources() -> dict[str, str]:
    """The deterministic math library (codegen/csrc), copied verbatim next to a unit."""
    sources = {}
    for fname in MATH_FILES:
        path = CSRC / fname
        if not path.is_file():
            raise CodegenError(f"{path}: missing (the deterministic math library sg_math is not installed)")
        sources[fname] = path.read_text(encoding="utf-8")
    return sources


def write_sources(sources: dict[str, str], out_dir: str | os.PathLike) -> list[Path]:
    """Write every file into out_dir (created if needed) all or nothing: each target is checked
    first (a directory or an unwritable place in the way is one CodegenError and nothing is
    written), then all are written to temporary siblings and renamed into place. Other files in
    out_dir are left alone."""
    out_dir = Path(out_dir)
    if out_dir.exists() and not out_dir.is_dir():
        raise CodegenError(f"--out: {out_dir} exists and is not a directory")
    targets = [out_dir / fname for fname in sorted(sources)]
    for path in targets:
        if path.is_symlink() or (path.exists() and not path.is_file()):
            raise CodegenError(f"--out: {path} exists and is not a regular file; nothing was written")
    try:
        return atomic.write_files({path: sources[path.name].encode("utf-8") for path in targets})
    except OSError as exc:
        raise CodegenError(f"--out: cannot write into {out_dir}: {exc.strerror or exc}; nothing was written") from None
