"""A small example room file, made by code rather than kept as a binary: a 6 m x 3 m x 5 m
room with a plinth, a ceiling light and two painting placeholders, in a node hierarchy with
translations, rotations, a non-uniform scale and a mirroring scale (so readers must apply the
transforms and the glTF winding rule).

    python -m gigascroll.room.example OUT.glb      # or .gltf, .obj, .ply

Nodes (parents first):
  gallery           root: translation (2, 0, -1), rotation 20 degrees about +y
    walls           a closed 6 x 3 x 5 m box, floor at y = 0, albedo (0.70, 0.68, 0.65)
    plinth          translation (1, 0.4, 0.5), 45 degrees about +y, scale (0.5, 0.8, 0.5) of a
                    unit cube, albedo (0.30, 0.30, 0.32)
    ceiling_rig     translation (0, 2.95, 0), scale (1, -1, 1): mirrors its children
      light         a 1.2 x 0.6 m quad, facing +y locally so -y (down) in the room;
                    emissiveFactor (1, 0.9, 0.8) x emissive strength 6
    back_wall_art   translation (0, 1.6, -2.49)
      painting:<first painting>   1.5 m wide at the painting's aspect, facing +z (the room)
    side_art        translation (-2.99, 1.5, 0), 90 degrees about +y
      side placeholder            extras {"painting": 1}: 1.0 m high, facing +x (the room)
    camera          translation (0, 1.6, 2), 10 degrees about +y, looking down its -z
"""

from __future__ import annotations

import math
import sys
from pathlib import Path

import numpy as np

from .sizes import painting_sizes

__all__ = ["EXAMPLE_PAINTINGS", "example_nodes", "write_example_room"]

# The paintings the example's placeholders are shaped for (name: width, height).
EXAMPLE_PAINTINGS = {"landscape": (3000, 2000), "hanging_scroll": (800, 2400)}


def _quaternion_y(degrees: float) -> list[float]:
    """glTF rotation (x, y, z, w) about +y."""
    h = math.radians(degrees) / 2
    return [0.0, math.sin(h), 0.0, math.cos(h)]


def _quad_facing_z(width: float, height: float) -> tuple[np.ndarray, np.ndarray]:
    """A width x height rectangle in the local xy plane centred at 0, facing +z (CCW)."""
    w, h = width / 2, height / 2
    v = np.array([[-w, -h, 0], [w, -h, 0], [w, h, 0], [-w, h, 0]], dtype=np.float64)
    return v, np.array([[0, 1, 2], [0, 2, 3]], dtype=np.int64)


def example_nodes(paintings=None) -> list[dict]:
    """The example room's nodes, in the form `write_gltf` takes."""
    import trimesh

    sizes = painting_sizes(EXAMPLE_PAINTINGS if paintings is None else paintings)
    if len(sizes) < 2:
        raise ValueError("the example room needs two paintings")
    walls = trimesh.creation.box(extents=(6.0, 3.0, 5.0))
    walls.apply_translation((0.0, 1.5, 0.0))
    walls.invert()  # facing into the room
    cube = trimesh.creation.box(extents=(1.0, 1.0, 1.0))
    light_v = np.array([[-0.6, 0, -0.3], [-0.6, 0, 0.3], [0.6, 0, 0.3], [0.6, 0, -0.3]])
    light_t = np.array([[0, 1, 2], [0, 2, 3]])  # counter-clockwise seen from +y
    first_v, first_t = _quad_facing_z(1.5, 1.5 / sizes[0].aspect)
    side_v, side_t = _quad_facing_z(1.0 * sizes[1].aspect, 1.0)
    return [
        dict(name="gallery", translation=[2.0, 0.0, -1.0], rotation=_quaternion_y(20.0),
             children=[1, 2, 3, 5, 7, 9]),
        dict(name="walls", vertices=walls.vertices, triangles=walls.faces,
             albedo=(0.70, 0.68, 0.65)),
        dict(name="plinth", translation=[1.0, 0.4, 0.5], rotation=_quaternion_y(45.0),
             scale=[0.5, 0.8, 0.5], vertices=cube.vertices, triangles=cube.faces,
             albedo=(0.30, 0.30, 0.32)),
        dict(name="ceiling_rig", translation=[0.0, 2.95, 0.0], scale=[1.0, -1.0, 1.0],
             children=[4]),
        dict(name="light", vertices=light_v, triangles=light_t, albedo=(0.8, 0.8, 0.8),
             emission=(6.0, 5.4, 4.8)),
        dict(name="back_wall_art", translation=[0.0, 1.6, -2.49], children=[6]),
        dict(name=f"painting:{sizes[0].name}", vertices=first_v, triangles=first_t),
        dict(name="side_art", translation=[-2.99, 1.5, 0.0], rotation=_quaternion_y(90.0),
             children=[8]),
        dict(name="side placeholder", vertices=side_v, triangles=side_t,
             extras={"painting": 1}),
        dict(name="camera", translation=[0.0, 1.6, 2.0], rotation=_quaternion_y(10.0),
             camera={"type": "perspective", "perspective": {"yfov": 1.0, "znear": 0.01}}),
    ]


def write_example_room(path, paintings=None) -> Path:
    """Write the example room as .glb or .gltf (the node hierarchy as above), or as .obj / .ply
    (the same room with the transforms applied, as those formats have none)."""
    from .files import load_room, save_room, write_gltf

    path = Path(path)
    suffix = path.suffix.lower()
    sizes = EXAMPLE_PAINTINGS if paintings is None else paintings
    if suffix in (".glb", ".gltf"):
        return write_gltf(example_nodes(sizes), path)
    if suffix in (".obj", ".ply"):
        glb = path.with_name(path.stem + ".example-tmp.glb")
        try:
            write_gltf(example_nodes(sizes), glb)
            spec = load_room(glb, sizes)
        finally:
            glb.unlink(missing_ok=True)
        return save_room(spec, path)
    raise ValueError(f"{path}: the example room is written as .glb, .gltf, .obj or .ply")


def main(argv=None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    if len(argv) != 1:
        print("usage: python -m gigascroll.room.example OUT.glb|.gltf|.obj|.ply",
              file=sys.stderr)
        return 2
    try:
        print(write_example_room(argv[0]))
    except (OSError, ValueError) as e:
        print(f"error: {e}", file=sys.stderr)
        return 2
    return 0


if __name__ == "__main__":
    sys.exit(main())
