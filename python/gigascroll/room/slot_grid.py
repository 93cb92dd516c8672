"""The points at which a painting's illuminance is computed: a grid of cell centres over its
slot, the same for the light specs' target solve (room/lights.py) and the `light` command's
maps, so that a light solved for a mean illuminance measures that mean."""

from __future__ import annotations

import math

import numpy as np

from .spec import PaintingSlot

__all__ = ["grid_shape", "slot_points", "slot_front"]


def grid_shape(slot: PaintingSlot, samples: int) -> tuple[int, int]:
    """(columns along u, rows along v): `samples` cells along the slot's longer side, square
    cells (at least 2 along the shorter)."""
    if isinstance(samples, bool) or not isinstance(samples, (int, np.integer)) \
            or not 2 <= samples <= 4096:
        raise ValueError(f"samples must be an integer in [2, 4096], got {samples!r}")
    w, h = float(slot.width_m), float(slot.height_m)
    if w >= h:
        return int(samples), max(2, min(int(samples), math.ceil(samples * h / w)))
    return max(2, min(int(samples), math.ceil(samples * w / h))), int(samples)


def slot_front(slot: PaintingSlot) -> np.ndarray:
    """The unit normal of the painting's visible side: v x u (u x v points into the wall)."""
    n = np.cross(np.asarray(slot.v_axis, np.float64), np.asarray(slot.u_axis, np.float64))
    return n / np.linalg.norm(n)


def slot_points(slot: PaintingSlot, samples: int) -> np.ndarray:
    """The cell centres of the grid_shape grid, (rows, columns, 3) world positions: row j,
    column i at origin + (i + 1/2) / columns * width * u + (j + 1/2) / rows * height * v
    (image x along u, image y down along v, as the painting's texels)."""
    cols, rows = grid_shape(slot, samples)
    o, u, v = (np.asarray(x, np.float64) for x in (slot.origin, slot.u_axis, slot.v_axis))
    s = (np.arange(cols) + 0.5) / cols * float(slot.width_m)
    t = (np.arange(rows) + 0.5) / rows * float(slot.height_m)
    return o + s[None, :, None] * u + t[:, None, None] * v
