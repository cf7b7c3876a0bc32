"""Errors a user can cause in the codegen layer (bad artifacts, bad parameters)."""


class CodegenError(Exception):
    """A user-facing error of the codegen layer."""
