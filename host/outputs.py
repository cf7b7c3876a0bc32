"""Output folders: the one rule every command that writes a folder follows.

A command writes a folder only when it is new, empty, or that command's own earlier output (a flight
package whose manifest lists everything in it; a simulation's metrics.json; a tuning folder's
tuning.json); anything else is refused in one line, because a folder written through
codegen.atomic.directory is replaced as a whole. A replaced folder must not be the current folder
or hold it, nor hold an input of the run. While it is written, the folder is locked (a second run
fails at once) and temporaries of killed runs are removed (codegen.atomic).
"""
from __future__ import annotations

import json
from pathlib import Path
from typing import Callable, Iterable

from codegen.package import manifest
from host.errors import HostError

MAX_MARKER_BYTES = 64 << 20

# owned(folder) -> None when the folder is the command's own output, else why it is not
Owner = Callable[[Path], "str | None"]


def package_owner(folder: Path) -> str | None:
    """A staregen flight package: a valid manifest, and nothing in the folder it does not list."""
    try:
        doc = manifest.load(folder)
    except manifest.PackageError as exc:
        return str(exc)
    listed = {manifest.MANIFEST, *doc["files"]}
    parents = {p.as_posix() for rel in listed for p in Path(rel).parents if p != Path(".")}
    for entry in sorted(folder.rglob("*")):
        rel = entry.relative_to(folder).as_posix()
        if entry.is_symlink() or not ((rel in parents and entry.is_dir()) or (rel in listed and entry.is_file())):
            return f"{rel} is not a file of the package's manifest"
    return None


def json_marker_owner(name: str) -> Owner:
    """An earlier output of a command whose folder always holds the JSON object `name`."""
    def owned(folder: Path) -> str | None:
        path = folder / name
        if path.is_symlink() or not path.is_file():
            return f"it holds no {name}"
        try:
            with path.open("rb") as fh:
                doc = json.loads(fh.read(MAX_MARKER_BYTES + 1))
        except (OSError, ValueError, RecursionError):
            return f"its {name} is not this command's"
        return None if isinstance(doc, dict) else f"its {name} is not this command's"
    return owned


def file_marker_owner(name: str) -> Owner:
    """A folder this command writes in place, recognised by the file `name` it creates first."""
    def owned(folder: Path) -> str | None:
        path = folder / name
        return None if path.is_file() and not path.is_symlink() else f"it holds no {name}"
    return owned


def _check_parents(out: Path) -> None:
    parent = out.resolve().parent
    for p in [parent, *parent.parents]:
        if p.exists():
            if not p.is_dir():
                raise HostError(f"cannot create output folder {out}: {p} is not a directory")
            break


def _check_not_holding(out: Path, inputs: Iterable[str | Path | None]) -> None:
    """A replaced folder goes as a whole: it must not hold the working folder or an input file."""
    where = out.resolve()
    cwd = Path.cwd().resolve()
    if where == cwd or where in cwd.parents:
        raise HostError(f"output folder {out} is the current folder or holds it; choose another folder")
    for path in inputs:
        if path is not None and where in Path(path).resolve().parents:
            raise HostError(f"input {path} lies inside output folder {out}, which is replaced; "
                            "choose another folder")


def check_output_folder(out: Path, owned: Owner, inputs: Iterable[str | Path | None] = (),
                        replaced: bool = True) -> None:
    """Refuse (HostError) a folder the command must not write: a file, a folder under a file, a
    non-empty folder that is not the command's own (`owned`), and, for a folder replaced as a whole,
    the current folder, one that holds it, or one that holds one of `inputs`."""
    out = Path(out)
    if out.exists() and not out.is_dir():
        raise HostError(f"output folder {out} exists and is not a directory")
    if replaced:
        _check_not_holding(out, inputs)
    if out.is_dir() and any(out.iterdir()):
        reason = owned(out)
        if reason is not None:
            raise HostError(f"output folder {out} is not empty and not this command's own output ({reason}); "
                            "refusing to write into it (choose a new or empty folder)")
    _check_parents(out)
