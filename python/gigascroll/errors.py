"""The error type of the command line: an error the user can fix (bad files, bad parameters)."""

from __future__ import annotations

__all__ = ["UserError", "expect_type"]


class UserError(Exception):
    """An error caused by the user's input: printed without a traceback."""


def expect_type(value, types, what: str):
    """TypeError naming `what` and the expected types unless `value` is an instance of `types`
    (a type or tuple of types); returns `value`. Public functions call it on their first
    arguments so a wrong object fails with one line instead of an AttributeError deep inside."""
    if not isinstance(value, types):
        kinds = types if isinstance(types, tuple) else (types,)
        names = " or ".join(t.__name__ for t in kinds)
        raise TypeError(f"{what} must be a {names}, not {type(value).__name__}")
    return value
