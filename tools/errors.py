"""Errors of the tools (corrupt ELF, missing symbol, emulator fault)."""


class ToolError(Exception):
    """A user-facing error of the tools layer."""
