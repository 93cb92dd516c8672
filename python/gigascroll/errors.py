"""The error type of the command line: an error the user can fix (bad files, bad parameters)."""

from __future__ import annotations

__all__ = ["UserError", "expect_type", "positive_float32"]


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


# The positive normal range of an IEEE 754 single: the core keeps these values as float32.
FLOAT32_MIN, FLOAT32_MAX = 2.0 ** -126, (2.0 - 2.0 ** -23) * 2.0 ** 127


def positive_float32(value, what: str) -> float:
    """`value` as a float, or ValueError unless it is a positive number that a float32 holds
    (between about 1.2e-38 and 3.4e38): a value that reaches the core as float32 must not turn
    into 0 (which may mean "automatic" there), a subnormal or infinity on the way."""
    try:
        v = float(value)
    except (TypeError, ValueError, OverflowError):
        raise ValueError(f"{what} must be a number, got {value!r}") from None
    if not FLOAT32_MIN <= v <= FLOAT32_MAX:  # NaN fails too
        raise ValueError(f"{what} must be positive, finite and in the range of a float32 "
                         f"[{FLOAT32_MIN:.3g}, {FLOAT32_MAX:.3g}], got {value!r}")
    return v
