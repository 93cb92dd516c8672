"""The automatic exposure of a room (display_mapping's `auto`): the median direct illuminance on
its paintings, computed from its emitting surfaces with Lambert's polygon formula (polygon.py),
so a white painting at that illuminance shows as paper white. Direct light only and unoccluded:
it is known before any photon is traced, the same for `render`, `gallery`, `view` and `serve`
of one room, and the interreflections (tens of percent) stay below the neutral curve's
compression."""

from __future__ import annotations

import math

import numpy as np

from ..display_mapping import LUMENS_PER_WATT, Display, ExposureSetting
from ..room.polygon import unit_irradiance
from ..room.spec import RoomSpec

__all__ = ["painting_lux", "auto_lux", "room_display", "FALLBACK_LUX"]

FALLBACK_LUX = 200.0    # a room whose paintings no light reaches directly: a gallery's level
GRID_STEP_M = 0.05      # points on each painting about every 5 cm, 3 to 64 a side
LUMA = np.array([0.2126, 0.7152, 0.0722])  # Rec. 709 luminance of linear RGB


def _emitter_triangles(room: RoomSpec):
    """(triangles (T, 3, 3), radiance (T, 3)) of the room's emitting surfaces: Lambert's
    formula holds for any convex polygon, a triangle too, each emitting toward the side its
    winding's normal points to (as the Gallery's emitters)."""
    tris, radiance = [], []
    for s in room.surfaces:
        if max(s.emission) <= 0:
            continue
        v, t = np.asarray(s.vertices, float), np.asarray(s.triangles, int)
        tris.append(v[t])
        radiance.append(np.tile(np.asarray(s.emission, float), (len(t), 1)))
    if not tris:
        return np.zeros((0, 3, 3)), np.zeros((0, 3))
    return np.concatenate(tris), np.concatenate(radiance)


def _irradiance(points, normal, quads) -> np.ndarray:
    """(P, Q) irradiance of unit-radiance triangles at points facing `normal`: the polygon
    formula, or for a triangle that crosses the points' horizon a midpoint rule over 256
    pieces with the receiver's cosine clamped at zero."""
    try:
        return unit_irradiance(points, normal, quads)
    except ValueError:
        pass
    out = np.zeros((len(points), len(quads)))
    n = np.asarray(normal, float)
    for q, quad in enumerate(quads):
        try:
            out[:, q] = unit_irradiance(points, n, quad[None])[:, 0]
            continue
        except ValueError:
            pass
        s = (np.arange(16) + 0.5) / 16
        a, b = np.meshgrid(s, s, indexing="ij")
        fold = a + b > 1                    # the square's far half folded onto the triangle
        a, b = np.where(fold, 1 - a, a), np.where(fold, 1 - b, b)
        e1, e2 = quad[1] - quad[0], quad[2] - quad[0]
        pts = quad[0] + a[..., None] * e1 + b[..., None] * e2
        area = np.linalg.norm(np.cross(e1, e2)) / 2 / 256
        ln = np.cross(e1, e2)
        ln /= np.linalg.norm(ln)
        r = pts.reshape(-1, 3)[None] - np.asarray(points)[:, None]      # (P, 256, 3)
        d2 = (r * r).sum(axis=2)
        cos_r = np.clip(r @ n, 0, None) / np.sqrt(d2)
        cos_l = np.clip(-(r @ ln), 0, None) / np.sqrt(d2)
        out[:, q] = (cos_r * cos_l / d2).sum(axis=1) * area
    return out


def painting_lux(room: RoomSpec) -> np.ndarray:
    """Direct illuminance (lux equivalent, Rec. 709 luminance) at a grid of points on every
    painting of the room, on the side of each painting its lights reach most."""
    quads, radiance = _emitter_triangles(room)
    values = []
    for slot in room.paintings:
        o, u, v = (np.asarray(x, float) for x in (slot.origin, slot.u_axis, slot.v_axis))
        nu = int(min(64, max(3, math.ceil(slot.width_m / GRID_STEP_M))))
        nv = int(min(64, max(3, math.ceil(slot.height_m / GRID_STEP_M))))
        a, b = (np.arange(nu) + 0.5) / nu, (np.arange(nv) + 0.5) / nv
        pts = (o + a[:, None, None] * slot.width_m * u
               + b[None, :, None] * slot.height_m * v).reshape(-1, 3)
        normal = np.cross(u, v)
        normal /= np.linalg.norm(normal)
        if not len(quads):
            values.append(np.zeros(len(pts)))
            continue
        sides = [(_irradiance(pts, s * normal, quads) @ radiance) @ LUMA for s in (1, -1)]
        best = max(sides, key=lambda e: float(e.sum()))
        values.append(best * LUMENS_PER_WATT)
    return np.concatenate(values) if values else np.zeros(0)


def auto_lux(room: RoomSpec) -> tuple[float, str]:
    """The reference illuminance of `auto` and how it was found: the median direct
    illuminance on the paintings; FALLBACK_LUX where no light reaches them directly."""
    lux = painting_lux(room)
    if lux.size and float(np.median(lux)) > 0:
        return float(np.median(lux)), "median direct illuminance on the paintings"
    if lux.size and float(lux.mean()) > 0:
        return float(lux.mean()), "mean direct illuminance on the paintings"
    return FALLBACK_LUX, "no direct light on the paintings: a gallery's 200 lux"


def room_display(room: RoomSpec | None, exposure: ExposureSetting | str = "auto",
                 tone: str = "neutral", lighting: str = "baked") -> Display:
    """The Display of a room's images. Lighting "unlit" (radiance = albedo, as if lit by
    pi W / m^2) exposes automatically for that light."""
    setting = exposure if isinstance(exposure, ExposureSetting) else ExposureSetting.parse(exposure)
    if setting.mode != "auto":
        return setting.display(0.0, tone)
    if lighting == "unlit" or room is None:
        return setting.display(math.pi * LUMENS_PER_WATT, tone, "unlit: radiance = albedo")
    lux, how = auto_lux(room)
    return setting.display(lux, tone, how)
