"""A room file's meshes as every reader hands them on: `Node`s in world space (metres, y up),
with the limits the readers and the assembly check them against.

The readers (gltf_nodes, obj_nodes, ply_nodes) turn a file into a list of `Node`s; files.py
assembles them into a `RoomSpec`, placeholders.py turns a placeholder node into a
`PaintingSlot`. `finite_numbers` and `world_mesh` are the checks the readers share.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

PAINTING_PREFIX = "painting:"
MAX_EXTENT_M = 10_000.0        # every vertex within 10 km of the origin
MIN_PAINTING_M = 1e-3          # a placeholder's sides are at least 1 mm ...
MAX_RADIANCE = 1e9             # ... and no emitter is brighter than this (W / m^2 / sr)
ASPECT_TOLERANCE = 0.01
PLANAR_TOLERANCE = 1e-4        # relative to the placeholder's diagonal (float32 positions)
GLB_MAGIC, GLB_JSON, GLB_BIN = 0x46546C67, 0x4E4F534A, 0x004E4942
CAMERA_MARK = "gigascroll_camera"  # marks the camera pseudo-node between reader and assembly


@dataclass
class Node:
    """One mesh instance of the file, in world space."""
    name: str
    vertices: np.ndarray
    triangles: np.ndarray
    albedo: tuple | None = None
    emission: tuple = (0.0, 0.0, 0.0)
    extras: dict = field(default_factory=dict)


def finite_numbers(values, n: int, path: Path, node: str, what: str, text: bool = False) -> tuple:
    """n finite numbers (JSON numbers; decimal strings only where the format is text: OBJ)."""
    try:
        if isinstance(values, (str, bytes)) or any(
                isinstance(x, bool) or isinstance(x, (str, bytes)) != text for x in values):
            raise TypeError
        out = tuple(float(x) for x in values)
        if len(out) != n:
            raise TypeError
    except (TypeError, ValueError):
        raise ValueError(f"{path}: node {node!r}: {what} must be {n} numbers, got "
                         f"{values!r}") from None
    if not all(math.isfinite(x) for x in out):
        raise ValueError(f"{path}: node {node!r}: {what} is not finite: {values!r}")
    return out


def world_mesh(path: Path, name: str, matrix, geometry) -> tuple[np.ndarray, np.ndarray]:
    m = np.asarray(matrix, dtype=np.float64)
    if not np.isfinite(m).all():
        raise ValueError(f"{path}: node {name!r} has a non-finite transform")
    v = np.asarray(geometry.vertices, dtype=np.float64)
    f = np.asarray(geometry.faces, dtype=np.int64).reshape(-1, 3)
    if not np.isfinite(v).all():
        raise ValueError(f"{path}: node {name!r} has non-finite vertices")
    with np.errstate(all="ignore"):
        world = v @ m[:3, :3].T + m[:3, 3]
    if not np.isfinite(world).all() or (len(world) and np.abs(world).max() > MAX_EXTENT_M):
        raise ValueError(f"{path}: node {name!r} reaches beyond {MAX_EXTENT_M:g} m "
                         f"(absurd size or transform)")
    if len(f) and (f.min() < 0 or f.max() >= len(v)):
        raise ValueError(f"{path}: node {name!r} has triangle indices out of range")
    used, local = np.unique(f, return_inverse=True)  # drop vertices no triangle uses
    world, f = world[used], local.reshape(-1, 3).astype(np.int64)
    if np.linalg.det(m[:3, :3]) < 0:
        f = f[:, ::-1].copy()  # a mirroring transform flips the winding (glTF 2.0, 3.7.4)
    return world, f
