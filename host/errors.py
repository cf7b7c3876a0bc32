"""Errors a user can cause (bad input, bad files); the CLI prints them as one line."""


class HostError(Exception):
    """A user-facing error of the host layer."""
