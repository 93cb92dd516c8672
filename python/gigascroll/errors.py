"""The error type of the command line: an error the user can fix (bad files, bad parameters)."""

from __future__ import annotations

__all__ = ["UserError"]


class UserError(Exception):
    """An error caused by the user's input: printed without a traceback."""
