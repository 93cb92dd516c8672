"""A PLY room file as `Node`s. PLY has no scene graph and no materials: one file holds the
whole room; the face property `surface` (int) indexes an element `surface` with float
properties albedo_r, albedo_g, albedo_b, emission_r, emission_g, emission_b and a list of
uchar `name` (UTF-8), one row per node. The header is checked before trimesh reads the body.
"""

from __future__ import annotations

import io
from pathlib import Path

import numpy as np

from .assets import MAX_VERTICES, check_triangles
from .nodes import Node, finite_numbers, world_mesh
from .placeholders import placeholder_key

__all__ = ["ply_nodes"]


def _check_ply_header(path: Path, data: bytes):
    """The PLY header's element counts within the budget, before trimesh allocates them (a
    face has at least one triangle)."""
    end = data.find(b"end_header", 0, 1 << 20)
    for line in data[:end if end >= 0 else 1 << 20].decode("ascii", "replace").splitlines():
        parts = line.split()
        if len(parts) == 3 and parts[0] == "element" and parts[2].isdigit():
            count = int(parts[2])
            if parts[1] == "face":
                check_triangles(path, count, " (faces)")
            elif count > MAX_VERTICES:
                raise ValueError(f"{path}: {count} {parts[1]} elements, more than {MAX_VERTICES}")


def ply_nodes(path: Path, data: bytes) -> list[Node]:
    import trimesh

    _check_ply_header(path, data)
    try:
        mesh = trimesh.load(io.BytesIO(data), file_type="ply", force="mesh", process=False)
        raw = mesh.metadata.get("_ply_raw", {})
        surface_of_face = np.asarray(raw["face"]["data"]["surface"], dtype=np.int64).reshape(-1)
        table = raw["surface"]["data"]
        rows = len(table["name"])
        columns = {k: np.asarray(table[k]) for k in ("albedo_r", "albedo_g", "albedo_b",
                                                       "emission_r", "emission_g", "emission_b")}
        names = [bytes(np.asarray(n, dtype=np.uint8)).decode("utf-8") for n in table["name"]]
    except OSError:
        raise
    except Exception as e:
        raise ValueError(f"{path}: trimesh cannot read it as a gigascroll PLY room (face "
                         f"property 'surface' and element 'surface'): {type(e).__name__}: "
                         f"{e}") from None
    faces = np.asarray(mesh.faces, dtype=np.int64)
    if len(surface_of_face) != len(faces) or (len(faces) and (
            surface_of_face.min() < 0 or surface_of_face.max() >= rows)):
        raise ValueError(f"{path}: face property 'surface' out of range")
    vertices, _ = world_mesh(path, path.name, np.eye(4), mesh)
    out = []
    for s in range(rows):
        tri = faces[surface_of_face == s]
        used, local = np.unique(tri, return_inverse=True)
        node = Node(names[s], vertices[used], local.reshape(-1, 3).astype(np.int64))
        if placeholder_key(node) is None:
            node.albedo = finite_numbers([columns[f"albedo_{c}"][s] for c in "rgb"], 3, path,
                                   names[s], "albedo")
            node.emission = finite_numbers([columns[f"emission_{c}"][s] for c in "rgb"], 3, path,
                                     names[s], "emission")
        out.append(node)
    return out
