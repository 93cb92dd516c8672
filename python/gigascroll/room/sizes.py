"""The paintings a room is built for: each one's name and shape, without the C++ core.

Built-in rooms and room files only need a painting's name and its width : height (to size a
slot, or to check a placeholder's aspect ratio). `painting_sizes` accepts what callers have at
hand: an open `TilePack` (its `.paintings`), a list of `PaintingSpec`s (which also give metres),
a list of (name, width, height) tuples, or a mapping name -> (width, height) or name -> aspect.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass


@dataclass(frozen=True)
class PaintingSize:
    """A painting's name and shape: width and height in texels (or any unit: only their ratio
    is used unless width_m / height_m, the physical size in metres, are given too)."""

    name: str
    width: float
    height: float
    width_m: float | None = None
    height_m: float | None = None

    @property
    def aspect(self) -> float:
        """Width / height."""
        if self.width_m is not None and self.height_m is not None:
            return self.width_m / self.height_m
        return self.width / self.height


def _positive(value, what: str) -> float:
    try:
        x = float(value)
    except (TypeError, ValueError):
        raise ValueError(f"{what} must be a number, got {value!r}") from None
    if not math.isfinite(x) or x <= 0:
        raise ValueError(f"{what} must be finite and > 0, got {value!r}")
    return x


def _one(name, shape, what: str) -> PaintingSize:
    if isinstance(shape, PaintingSize):
        return shape
    if hasattr(shape, "width") and hasattr(shape, "height"):  # PaintingSpec, PackPainting
        wm, hm = getattr(shape, "width_m", None), getattr(shape, "height_m", None)
        return PaintingSize(
            str(getattr(shape, "name", name)), _positive(shape.width, f"{what} width"),
            _positive(shape.height, f"{what} height"),
            None if wm is None else _positive(wm, f"{what} width_m"),
            None if hm is None else _positive(hm, f"{what} height_m"))
    if isinstance(shape, (int, float)) and not isinstance(shape, bool):  # an aspect ratio
        return PaintingSize(str(name), _positive(shape, f"{what} aspect"), 1.0)
    try:
        w, h = shape
    except (TypeError, ValueError):
        raise ValueError(f"{what}: expected (width, height), an aspect ratio or an object with "
                         f"width and height, got {shape!r}") from None
    return PaintingSize(str(name), _positive(w, f"{what} width"), _positive(h, f"{what} height"))


def painting_sizes(paintings) -> list[PaintingSize]:
    """The paintings as a list (index = painting id of the pack); see the module docstring."""
    if hasattr(paintings, "paintings") and not isinstance(paintings, Mapping):  # a TilePack
        paintings = list(paintings.paintings)
    if isinstance(paintings, Mapping):
        result = [_one(name, shape, f"painting {name!r}") for name, shape in paintings.items()]
    else:
        try:
            items = list(paintings)
        except TypeError:
            raise ValueError(f"paintings: expected a TilePack, a list or a mapping, got "
                             f"{type(paintings).__name__}") from None
        result = []
        for i, item in enumerate(items):
            if isinstance(item, tuple) and len(item) == 3 and isinstance(item[0], str):
                result.append(_one(item[0], item[1:], f"painting {item[0]!r}"))
            else:
                result.append(_one(f"painting_{i}", item, f"painting {i}"))
    if not result:
        raise ValueError("paintings: no painting given")
    return result
