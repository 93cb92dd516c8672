"""What a gallery room is made of, before it becomes a `Gallery` in the core.

Built-in rooms (`scroll`, `hall`) and room files (glTF / OBJ / PLY through trimesh) both produce
a `RoomSpec`; `Gallery.from_room(spec, pack)` turns it into the one Embree scene. Lengths are in
metres, y is up. Surfaces are Lambertian and two-sided; emission is one-sided, toward the side
the triangle winding's normal points to (as in the photon `Scene`).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np


@dataclass
class Surface:
    """A Lambertian triangle mesh: vertices (n, 3) float64, triangles (m, 3) int64 into them,
    albedo in [0, 1) per channel, emitted radiance (W / m^2 / sr per channel, >= 0)."""

    name: str
    vertices: np.ndarray
    triangles: np.ndarray
    albedo: tuple[float, float, float]
    emission: tuple[float, float, float] = (0.0, 0.0, 0.0)


@dataclass
class PaintingSlot:
    """A rectangle that shows a painting of the pack. Texel (0, 0) is at `origin`; image x runs
    along the unit vector `u_axis` for `width_m` metres, image y (downwards in the image) along
    the unit vector `v_axis` for `height_m` metres. Seen unmirrored (image x to the viewer's
    right, image y down), u x v points away from the viewer, into the wall; the painting is
    two-sided, so only its plane matters to the gallery. `painting` names the painting of the
    pack by name (str) or index (int)."""

    painting: str | int
    origin: tuple[float, float, float]
    u_axis: tuple[float, float, float]
    v_axis: tuple[float, float, float]
    width_m: float
    height_m: float
    name: str = ""


@dataclass
class RoomSpec:
    """A room: its surfaces, its painting slots, a suggested first camera, and the light specs
    (room/lights.py `LightSpec`) its emitting surfaces were made from, where known."""

    name: str
    surfaces: list[Surface] = field(default_factory=list)
    paintings: list[PaintingSlot] = field(default_factory=list)
    camera_eye: tuple[float, float, float] | None = None
    camera_target: tuple[float, float, float] | None = None
    lights: list = field(default_factory=list)
