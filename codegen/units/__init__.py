"""The registry of generated units: one folder per unit below this package.

A unit folder's `__init__.py` defines `KIND` (a codegen.unit.UnitKind); `kinds()` imports every
folder here and collects them, so adding a unit is adding its folder. A folder under construction
says so with `KIND = None` (as `gp` did while only its artifact existed) and is not registered;
a folder without `KIND` is an error, not a silently missing unit. A unit that lives
elsewhere (a user's own, or a test's throw-away one) calls `register(kind)` once.
"""
from __future__ import annotations

import importlib
import pkgutil

from codegen.errors import CodegenError
from codegen.unit import UnitKind

_registered: dict[str, UnitKind] = {}
_discovered = False


def register(kind: UnitKind) -> UnitKind:
    """Add a unit kind; a second, different kind under the same name is an error."""
    if not isinstance(kind, UnitKind):
        raise CodegenError(f"register: expected a UnitKind, got {type(kind).__name__}")
    known = _registered.get(kind.name)
    if known is not None and known is not kind:
        raise CodegenError(f"unit {kind.name!r} is registered twice")
    _registered[kind.name] = kind
    return kind


def unregister(name: str) -> None:
    """Remove a registered kind (for throw-away units in tests)."""
    _registered.pop(name, None)


def _discover() -> None:
    global _discovered
    if _discovered:
        return
    for info in sorted(pkgutil.iter_modules(__path__), key=lambda m: m.name):
        if info.ispkg:
            module = importlib.import_module(f"{__name__}.{info.name}")
            if not hasattr(module, "KIND"):
                raise CodegenError(f"codegen/units/{info.name}: defines no KIND (a UnitKind, or None while "
                                   "the unit is under construction)")
            if module.KIND is not None:
                register(module.KIND)
    _discovered = True


def kinds() -> dict[str, UnitKind]:
    """Every registered unit kind by name, the built-in folders first."""
    _discover()
    return dict(_registered)


def get(name: str) -> UnitKind:
    known = kinds()
    if name not in known:
        raise CodegenError(f"unknown unit {name!r} (known: {', '.join(sorted(known))})")
    return known[name]


def configure(kind: str, /, **inputs):
    """The unit `kind` bound to its inputs (see UnitKind.configure)."""
    return get(kind).configure(**inputs)
