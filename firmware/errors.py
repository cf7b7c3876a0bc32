"""Errors of the builds (missing toolchain, compiler failure)."""


class FirmwareError(Exception):
    """A user-facing error of the firmware builds."""
