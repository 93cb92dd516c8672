"""Lambert's formula for the irradiance a planar polygon of uniform radiance gives a point:
the exact direct light of the gallery's rectangular lights, which the built-in rooms and the
light specs (room/lights.py) solve their emission with, and the tests' analytic reference."""

from __future__ import annotations

import numpy as np

__all__ = ["polygon_irradiance", "unit_irradiance"]


def polygon_irradiance(point, normal, polygon) -> float:
    """Irradiance at `point` (receiver facing unit `normal`) from a planar convex polygon of
    unit radiance that emits on the side its winding's normal points to (counter-clockwise seen
    from the front). Lambert's formula: E = 1/2 sum_i theta_i (n . g_i), g_i the unit normal of
    the plane through the point and edge i. The polygon must lie wholly above the receiver's
    horizon (all the rooms here place lights so)."""
    return float(unit_irradiance([point], normal, [polygon])[0, 0])


def unit_irradiance(points, normal, polygons) -> np.ndarray:
    """polygon_irradiance for P points (one receiver normal) and Q polygons of as many corners
    each: a (P, Q) array."""
    p = np.asarray(points, dtype=np.float64).reshape(-1, 3)
    n = np.asarray(normal, dtype=np.float64)
    poly = np.asarray(polygons, dtype=np.float64)                     # (Q, K, 3)
    light_normal = np.cross(poly[:, 1] - poly[:, 0], poly[:, 2] - poly[:, 0])
    facing = np.einsum("pqk,qk->pq", p[:, None] - poly[None, :, 0], light_normal) > 0
    r = poly[None] - p[:, None, None]                                 # (P, Q, K, 3)
    if np.any((r @ n <= 0).any(axis=2) & facing):
        raise ValueError("polygon_irradiance: the light crosses the receiver's horizon")
    r /= np.linalg.norm(r, axis=3, keepdims=True)
    nxt = np.roll(r, -1, axis=2)
    theta = np.arccos(np.clip((r * nxt).sum(axis=3), -1.0, 1.0))
    g = np.cross(r, nxt)
    g /= np.linalg.norm(g, axis=3, keepdims=True)
    total = (theta * (g @ n)).sum(axis=2)
    return np.where(facing, np.abs(total) / 2.0, 0.0)
