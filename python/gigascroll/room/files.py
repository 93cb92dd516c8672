"""Rooms from files: glTF 2.0 (.gltf / .glb), OBJ (+ .mtl) and PLY, read through trimesh, as a
`RoomSpec` (`load_room`); and `save_room` (save.py), which writes a `RoomSpec` back as such a file.

Before trimesh reads anything, the file is checked from its structure: every file it names
is a regular file, read safely and only if used (assets.py); a glTF file follows the glTF 2.0
specification (its JSON Schema and the rules beyond it) and its drawn instances fit the
triangle budget, counted from the node graph and the accessors' counts (gltf.py); OBJ faces
and PLY elements are counted from the text. The budget is what the gallery can bake
(assets.MAX_TRIANGLES).

Each format has its reader, which hands on the file's meshes as `Node`s in world space
(gltf_nodes.py, obj_nodes.py, ply_nodes.py: transforms, winding and materials are described
there); this module assembles them. A node that is a painting placeholder becomes a
`PaintingSlot` (placeholders.py); any other node with triangles a `Surface` of the albedo and
emission its material gives (albedo in [0, 1) per channel, emission radiance in W / m^2 / sr).

glTF light nodes: a node whose extras hold {"light": {"kelvin": K, "lumens": F}} or {"light":
{"kelvin": K, "lux": E, "painting": KEY}} is a `LightSpec` (room/lights.py): its triangles are
the panels (emitting toward their winding normal), its material gives the albedo, and its
emission is solved for the luminous flux F or for the mean direct illuminance E on the slot (or
painting) KEY; kelvin may be left out (white). Any emissiveFactor of the node is replaced.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from .assets import MAX_FILE_BYTES, check_triangles, read_regular
from .gltf_nodes import gltf_nodes
from .lights import light_from_extras, light_surface
from .nodes import CAMERA_MARK, MAX_RADIANCE, PAINTING_PREFIX, Node
from .obj_nodes import obj_nodes
from .placeholders import placeholder_key, placeholder_slot
from .ply_nodes import ply_nodes
from .save import save_room, write_gltf
from .sizes import painting_sizes
from .spec import PaintingSlot, RoomSpec, Surface

__all__ = ["load_room", "save_room", "write_gltf", "ROOM_FILE_SUFFIXES", "PAINTING_PREFIX"]

ROOM_FILE_SUFFIXES = (".glb", ".gltf", ".obj", ".ply")


def load_room(path, paintings, name: str | None = None) -> RoomSpec:
    """The room in a .glb / .gltf / .obj / .ply file (see the module docstring).
    `paintings`: the pack's paintings (a TilePack, a list or a mapping; see `painting_sizes`),
    used to bind and check the placeholders. Bad files raise OSError (missing / unreadable) or
    ValueError (anything else), naming the file and the node."""
    path = Path(path)
    sizes = painting_sizes(paintings)
    suffix = path.suffix.lower()
    if suffix not in ROOM_FILE_SUFFIXES:
        raise ValueError(f"{path}: unknown room file type {suffix!r} (want one of "
                         f"{', '.join(ROOM_FILE_SUFFIXES)})")
    try:
        data = read_regular(path, f"{path}: room file", MAX_FILE_BYTES)
    except FileNotFoundError:
        raise FileNotFoundError(f"{path}: no such room file") from None
    reader = {".glb": gltf_nodes, ".gltf": gltf_nodes, ".obj": obj_nodes, ".ply": ply_nodes}
    try:
        with np.errstate(all="ignore"):  # hostile transforms overflow inside trimesh; checked after
            nodes = reader[suffix](path, data)
    except (TypeError, KeyError, IndexError, AttributeError, OverflowError) as e:
        # a JSON value of the wrong shape that the checks above did not anticipate
        raise ValueError(f"{path}: malformed room file: {type(e).__name__}: {e}") from None
    spec = room_from_nodes(path, nodes, sizes, path.stem)
    if name:
        spec.name = name
    return spec


def room_from_nodes(path: Path, nodes: list[Node], sizes, name: str) -> RoomSpec:
    surfaces, slots, light_nodes = [], [], []
    total = 0
    used_names = set()
    eye = target = None
    for node in nodes:
        if node.extras.get(CAMERA_MARK) is True and len(node.triangles) == 0:
            eye, target = node.extras.get("eye"), node.extras.get("target")
            name = node.extras.get("scene") or name
            continue
        total += len(node.triangles)
        check_triangles(path, total)
        if placeholder_key(node) is not None:
            slots.append(placeholder_slot(node, sizes, path))
            continue
        if len(node.triangles) == 0:
            continue
        if "light" in node.extras:
            light_nodes.append(node)
            continue
        albedo, emission = node.albedo, node.emission
        if not all(0 <= a < 1 for a in albedo):
            raise ValueError(f"{path}: node {node.name!r}: albedo {albedo} must be in [0, 1) "
                             f"per channel (>= 1 creates energy)")
        if not all(0 <= e <= MAX_RADIANCE for e in emission):
            raise ValueError(f"{path}: node {node.name!r}: emission {emission} must be in "
                             f"[0, {MAX_RADIANCE:g}] W/m^2/sr")
        surface_name = node.name
        k = 1
        while surface_name in used_names:
            surface_name, k = f"{node.name}#{k}", k + 1
        used_names.add(surface_name)
        surfaces.append(Surface(surface_name, np.ascontiguousarray(node.vertices),
                                np.ascontiguousarray(node.triangles), tuple(albedo),
                                tuple(emission)))
    lights = _lights(path, light_nodes, slots, used_names)
    surfaces += [surface for _, surface in lights]
    if not any(max(s.emission) > 0 for s in surfaces):
        raise ValueError(f"{path}: the room has no light (no node with emission > 0)")
    return RoomSpec(name, surfaces, slots, camera_eye=eye, camera_target=target,
                    lights=[light for light, _ in lights])


def _lights(path: Path, nodes: list[Node], slots: list[PaintingSlot], used_names: set) -> list:
    """(LightSpec, its Surface) of each light node (extras "light"), solved once every
    painting slot is known."""
    result = []
    for node in nodes:
        if not all(0 <= a < 1 for a in node.albedo):
            raise ValueError(f"{path}: node {node.name!r}: albedo {node.albedo} must be in "
                             f"[0, 1) per channel (>= 1 creates energy)")
        name, k = node.name, 1
        while name in used_names:
            name, k = f"{node.name}#{k}", k + 1
        used_names.add(name)
        try:
            light = light_from_extras(name, list(node.vertices[node.triangles]),
                                      node.extras["light"], node.albedo)
            result.append((light, light_surface(light, slots)))
        except ValueError as e:
            raise ValueError(f"{path}: {e}") from None
    return result
