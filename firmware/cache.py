"""What the x86 and ARM build caches share: content hashes of built files, and discarding an entry
that no longer matches its manifest (a truncated module would crash the loader with SIGBUS; an
edited ELF would be measured as if it were the generated code)."""
from __future__ import annotations

import hashlib
import os
import shutil
from pathlib import Path


def file_sha256(path: Path) -> str:
    h = hashlib.sha256()
    with open(path, "rb") as fh:
        for block in iter(lambda: fh.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()


def discard(folder: Path) -> None:
    """Move a bad cache entry out of the way (atomic rename), then delete it."""
    trash = folder.with_name(f".{folder.name}.{os.getpid()}.bad")
    try:
        os.rename(folder, trash)
    except OSError:
        return   # another process replaced it meanwhile
    shutil.rmtree(trash, ignore_errors=True)
