"""Painting placeholders: a room file's node named `painting:<key>` or whose glTF extras hold
{"painting": <key>} (key: a painting's name, or its index as an int or a decimal string)
becomes a `PaintingSlot` (and no Surface; the wall behind it is a node of its own).

Its mesh must be one planar rectangle: exactly four corners and two triangles that cover it,
both facing the same way. Its front is the side the triangles' normal points to
(counter-clockwise winding seen from the front). The image is placed so that it reads
unmirrored from the front with the project's camera (right = forward x up): texel (0, 0) is
the top-left corner seen from the front, u_axis (image x) runs to the right and v_axis (image
y) down, so front = v x u. "Up" is world +y projected into the placeholder's plane, or world
-z for a placeholder within ~25 degrees of horizontal (a painting on a table reads with its top
towards -z), or the vector in extras {"up": [x, y, z]}; v_axis is the rectangle edge closest to
down. The rectangle's aspect (along u : along v) must be within 1 % of the painting's.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from .nodes import (ASPECT_TOLERANCE, MIN_PAINTING_M, PAINTING_PREFIX, PLANAR_TOLERANCE, Node,
                    finite_numbers)
from .sizes import PaintingSize
from .spec import PaintingSlot

__all__ = ["placeholder_key", "placeholder_slot"]


def placeholder_key(node: Node):
    """The painting key of a placeholder node (str or int), or None."""
    if "painting" in node.extras:
        return node.extras["painting"]
    if node.name.startswith(PAINTING_PREFIX):
        return node.name[len(PAINTING_PREFIX):]
    return None


def _resolve_painting(key, sizes: list[PaintingSize], path: Path, node: str) -> int | str:
    """A painting name, else a decimal index; `name#tag` names one of several placeholders
    of the same painting (node names must be unique in OBJ and PLY)."""
    if isinstance(key, str):
        for k in (key, key.rpartition("#")[0]) if "#" in key else (key,):
            if any(p.name == k for p in sizes):
                return k
            if k.isdigit() and int(k) < len(sizes):
                return int(k)
    elif isinstance(key, int) and not isinstance(key, bool) and 0 <= key < len(sizes):
        return key
    raise ValueError(f"{path}: placeholder {node!r}: no painting {key!r} among the "
                     f"{len(sizes)} paintings ({', '.join(p.name for p in sizes[:8])}"
                     f"{', ...' if len(sizes) > 8 else ''})")


def placeholder_slot(node: Node, sizes: list[PaintingSize], path: Path) -> PaintingSlot:
    key = _resolve_painting(placeholder_key(node), sizes, path, node.name)
    painting = sizes[key] if isinstance(key, int) else next(p for p in sizes if p.name == key)
    what = f"{path}: placeholder {node.name!r}"
    v, f = node.vertices, node.triangles
    if len(f) != 2:
        raise ValueError(f"{what} must be one rectangle of two triangles, has {len(f)}")
    scale = float(np.ptp(v[f.reshape(-1)], axis=0).max()) if len(v) else 0.0
    if not scale > 0:
        raise ValueError(f"{what} is degenerate (zero size)")
    # Corners: the triangles' vertices, merged within a tolerance (files may duplicate them).
    corners = []
    for p in v[f.reshape(-1)]:
        if not any(np.linalg.norm(p - c) <= PLANAR_TOLERANCE * scale for c in corners):
            corners.append(p)
    if len(corners) != 4:
        raise ValueError(f"{what} must have exactly four corners, has {len(corners)}")
    t = v[f]
    normals = np.cross(t[:, 1] - t[:, 0], t[:, 2] - t[:, 0])
    areas = np.linalg.norm(normals, axis=1)
    if areas.min() <= (PLANAR_TOLERANCE * scale) ** 2:
        raise ValueError(f"{what} has a degenerate triangle")
    if np.dot(normals[0], normals[1]) <= 0:
        raise ValueError(f"{what}: its two triangles face opposite ways")
    n = normals.sum(axis=0)
    n /= np.linalg.norm(n)
    corners = np.array(corners)
    centre = corners.mean(axis=0)
    if np.abs((corners - centre) @ n).max() > PLANAR_TOLERANCE * scale or \
            (normals / areas[:, None] @ n).min() < 1 - 1e-6:
        raise ValueError(f"{what} is not planar (or its two triangles face opposite ways)")
    # A rectangle: the corners' centroid is the midpoint of both diagonals, which are equal.
    order = np.argsort(np.arctan2(*((corners - centre) @ _plane_basis(n)).T[::-1]))
    c = corners[order]
    diagonals = (np.linalg.norm(c[2] - c[0]), np.linalg.norm(c[3] - c[1]))
    e1, e2 = c[1] - c[0], c[3] - c[0]
    if abs(diagonals[0] - diagonals[1]) > PLANAR_TOLERANCE * scale or \
            np.linalg.norm(c[0] + c[2] - c[1] - c[3]) > PLANAR_TOLERANCE * scale or \
            abs(np.dot(e1, e2)) > PLANAR_TOLERANCE * scale * scale:
        raise ValueError(f"{what} is not a rectangle")
    # Cover it: the triangles' corners (in c's counter-clockwise order) share one diagonal.
    corner_of = [int(np.argmin(np.linalg.norm(c - p, axis=1))) for p in v[f.reshape(-1)]]
    a, b = set(corner_of[:3]), set(corner_of[3:])
    shared = sorted(a & b)
    if len(a) != 3 or len(b) != 3 or len(shared) != 2 or shared[1] - shared[0] != 2 or \
            abs(areas.sum() / 2 - np.linalg.norm(e1) * np.linalg.norm(e2)) > \
            1e-3 * areas.sum() / 2:
        raise ValueError(f"{what}: its two triangles do not cover the rectangle")
    up = _up_of(node, n, path)
    down = -(up - np.dot(up, n) * n)
    edges = [e / np.linalg.norm(e) for e in (e1, e2)]
    v_axis = max((s * e for e in edges for s in (1.0, -1.0)), key=lambda d: np.dot(d, down))
    u_axis = np.cross(n, v_axis)
    coords = (c - centre) @ np.stack([u_axis, v_axis]).T
    origin = c[np.argmin(coords[:, 0] + coords[:, 1])]
    width, height = float(np.ptp(coords[:, 0])), float(np.ptp(coords[:, 1]))
    if min(width, height) < MIN_PAINTING_M:
        raise ValueError(f"{what} is {width:.3g} m x {height:.3g} m, smaller than "
                         f"{MIN_PAINTING_M * 1000:g} mm")
    aspect = width / height
    if abs(aspect / painting.aspect - 1) > ASPECT_TOLERANCE:
        raise ValueError(f"{what}: aspect {aspect:.5g} (width along u / height along v, "
                         f"{width:.4g} m x {height:.4g} m) differs from painting "
                         f"{painting.name!r}'s {painting.aspect:.5g} by more than "
                         f"{ASPECT_TOLERANCE:.0%}")
    return PaintingSlot(key, tuple(float(x) for x in origin), tuple(float(x) for x in u_axis),
                        tuple(float(x) for x in v_axis), width, height, name=node.name)


def _plane_basis(n: np.ndarray) -> np.ndarray:
    a = np.eye(3)[np.argmin(np.abs(n))]
    x = np.cross(n, a)
    x /= np.linalg.norm(x)
    return np.stack([x, np.cross(n, x)]).T


def _up_of(node: Node, n: np.ndarray, path: Path) -> np.ndarray:
    if "up" in node.extras:
        up = np.array(finite_numbers(node.extras["up"], 3, path, node.name, "extras.up"))
        if np.linalg.norm(up - np.dot(up, n) * n) < 1e-6 * max(np.linalg.norm(up), 1e-300):
            raise ValueError(f"{path}: placeholder {node.name!r}: extras.up is along its normal")
        return up / np.linalg.norm(up)
    world_up = np.array([0.0, 1.0, 0.0])
    if abs(n[1]) > math.cos(math.radians(25.0)):
        return np.array([0.0, 0.0, -1.0])
    return world_up
